#include "tools/common/revision.hpp"

namespace rigctl {

// Weak: the program links the build's revision (tools/revision_of_build.cpp,
// rewritten at every build); anything else linking the run library (the
// tests) records "unknown". Only the program relinks when a commit changes
// the revision, not every test that links the run library.
__attribute__((weak)) const char* rigctl_revision() { return "unknown"; }

}  // namespace rigctl
