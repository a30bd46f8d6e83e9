// rigctl's git revision as the build saw it (`git describe --always --dirty`,
// e.g. "c0b3b3b1a2f4-dirty"; "unknown" outside a git checkout). The run
// catalog records it with every run, so a changed result can be traced to
// the program that produced it.
#pragma once

namespace rigctl {

const char* rigctl_revision();

}  // namespace rigctl
