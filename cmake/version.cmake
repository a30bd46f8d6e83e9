# `rigctl --version`: the project's version and the git revision it was
# configured from (`git describe --always --dirty`). Without git or outside a
# git checkout (a source tarball) the revision reads "unknown". Configuring
# again after a commit updates it: the checkout's HEAD and its branch ref are
# configure dependencies.
set(RIGCTL_GIT_REVISION "unknown")
find_package(Git QUIET)
if(GIT_FOUND)
  execute_process(COMMAND "${GIT_EXECUTABLE}" describe --always --dirty --abbrev=12
                  WORKING_DIRECTORY "${PROJECT_SOURCE_DIR}"
                  OUTPUT_VARIABLE _describe OUTPUT_STRIP_TRAILING_WHITESPACE
                  RESULT_VARIABLE _describe_rc ERROR_QUIET)
  if(_describe_rc EQUAL 0 AND NOT _describe STREQUAL "")
    set(RIGCTL_GIT_REVISION "${_describe}")
    execute_process(COMMAND "${GIT_EXECUTABLE}" rev-parse --symbolic-full-name HEAD
                    WORKING_DIRECTORY "${PROJECT_SOURCE_DIR}" OUTPUT_VARIABLE _branch
                    OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
    foreach(_name HEAD ${_branch} packed-refs)
      execute_process(COMMAND "${GIT_EXECUTABLE}" rev-parse --path-format=absolute --git-path "${_name}"
                      WORKING_DIRECTORY "${PROJECT_SOURCE_DIR}" OUTPUT_VARIABLE _path
                      OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
      if(EXISTS "${_path}")
        set_property(DIRECTORY "${PROJECT_SOURCE_DIR}" APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS "${_path}")
      endif()
    endforeach()
  endif()
endif()
set(RIGCTL_VERSION_TEXT "rigctl ${PROJECT_VERSION} (git ${RIGCTL_GIT_REVISION})")
configure_file("${CMAKE_CURRENT_LIST_DIR}/rigctl_version.hpp.in" "${PROJECT_BINARY_DIR}/generated/rigctl_version.hpp" @ONLY)
