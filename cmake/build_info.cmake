# Writes the build-information header (run at build time by the
# pumasim_build_info target: cmake -D... -P cmake/build_info.cmake).
# Inputs: SOURCE_DIR, OUTPUT, COMPILER_ID, COMPILER_VERSION, BUILD_TYPE, FLAGS.
# The git revision is read here, when the program is built, never at run time;
# "-dirty" is appended when the tree has changes. The header is rewritten only
# when its content changes (file(CONFIGURE) leaves an identical file alone), so
# a build with nothing new recompiles nothing.
find_package(Git QUIET)
set(PUMASIM_GIT_REVISION "unknown")
set(PUMASIM_GIT_DIRTY "false")
if(GIT_FOUND)
  execute_process(COMMAND ${GIT_EXECUTABLE} -C ${SOURCE_DIR} rev-parse --short HEAD
                  OUTPUT_VARIABLE _rev RESULT_VARIABLE _rc ERROR_QUIET OUTPUT_STRIP_TRAILING_WHITESPACE)
  if(_rc EQUAL 0 AND NOT _rev STREQUAL "")
    set(PUMASIM_GIT_REVISION "${_rev}")
    execute_process(COMMAND ${GIT_EXECUTABLE} -C ${SOURCE_DIR} status --porcelain
                    OUTPUT_VARIABLE _status RESULT_VARIABLE _rc ERROR_QUIET OUTPUT_STRIP_TRAILING_WHITESPACE)
    if(_rc EQUAL 0 AND NOT _status STREQUAL "")
      set(PUMASIM_GIT_DIRTY "true")
      string(APPEND PUMASIM_GIT_REVISION "-dirty")
    endif()
  endif()
endif()

# C string literals: backslashes and quotes escaped, runs of spaces collapsed.
function(pumasim_c_string out value)
  string(STRIP "${value}" value)
  string(REGEX REPLACE "  +" " " value "${value}")
  string(REPLACE "\\" "\\\\" value "${value}")
  string(REPLACE "\"" "\\\"" value "${value}")
  set(${out} "${value}" PARENT_SCOPE)
endfunction()
pumasim_c_string(PUMASIM_FLAGS "${FLAGS}")
pumasim_c_string(PUMASIM_COMPILER "${COMPILER_ID} ${COMPILER_VERSION}")
pumasim_c_string(PUMASIM_BUILD_TYPE "${BUILD_TYPE}")

file(CONFIGURE OUTPUT "${OUTPUT}" @ONLY CONTENT [[
// Generated at build time by cmake/build_info.cmake: do not edit.
#pragma once

namespace pumasim::build_info {
inline constexpr const char* kGitRevision = "@PUMASIM_GIT_REVISION@";  // + "-dirty" with uncommitted changes
inline constexpr bool kGitDirty = @PUMASIM_GIT_DIRTY@;
inline constexpr const char* kCompiler = "@PUMASIM_COMPILER@";   // CMAKE_CXX_COMPILER_ID and _VERSION
inline constexpr const char* kFlags = "@PUMASIM_FLAGS@";         // CMAKE_CXX_FLAGS, _<CONFIG>, native tuning
inline constexpr const char* kBuildType = "@PUMASIM_BUILD_TYPE@";
}  // namespace pumasim::build_info
]])
