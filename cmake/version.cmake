# `rigctl --version`: the project's version, written at configure time. The
# git revision beside it is the build's own (tools/scripts/revision.cmake,
# rewritten at every build and compiled into the program alone), the same
# one the run catalog records with every run.
configure_file("${CMAKE_CURRENT_LIST_DIR}/rigctl_version.hpp.in" "${PROJECT_BINARY_DIR}/generated/rigctl_version.hpp" @ONLY)
