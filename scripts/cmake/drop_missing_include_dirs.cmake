# Work around a defect of the ROS 2 PyPI wheels (ros-jazzy-*), injected with
#   cmake -DCMAKE_PROJECT_INCLUDE=<this file> ...
#
# The CMake config files those wheels export list, on some imported targets (notably
# <pkg>::<pkg>__rosidl_generator_py), include directories of the container the wheels were built in, such as
# /opt/python/cp311-cp311/include/python3.11. They do not exist on a user's machine, and CMake's generate step then
# fails with "Imported target ... includes non-existent path".
#
# This file runs right after project(); it defers a function to the end of the top-level directory, when every
# find_package() has run, that removes non-existent paths from INTERFACE_INCLUDE_DIRECTORIES of all imported targets.
# No package is edited; the paths a target really needs exist and are kept.

include_guard(GLOBAL)

# Removes non-existent entries from the INTERFACE_INCLUDE_DIRECTORIES of the imported targets of DIR and of its
# subdirectories. Entries holding generator expressions are kept as they are.
function(_sigcore_drop_missing_include_dirs dir)
  get_property(_targets DIRECTORY "${dir}" PROPERTY IMPORTED_TARGETS)
  foreach(_target IN LISTS _targets)
    get_target_property(_dirs ${_target} INTERFACE_INCLUDE_DIRECTORIES)
    if(NOT _dirs)
      continue()
    endif()
    set(_kept "")
    set(_changed FALSE)
    foreach(_d IN LISTS _dirs)
      if(_d MATCHES "\\$<" OR EXISTS "${_d}")
        list(APPEND _kept "${_d}")
      else()
        set(_changed TRUE)
        message(STATUS "sigcore: dropping non-existent include directory '${_d}' of imported target ${_target}")
      endif()
    endforeach()
    if(_changed)
      set_property(TARGET ${_target} PROPERTY INTERFACE_INCLUDE_DIRECTORIES "${_kept}")
    endif()
  endforeach()
  get_property(_subdirs DIRECTORY "${dir}" PROPERTY SUBDIRECTORIES)
  foreach(_sub IN LISTS _subdirs)
    _sigcore_drop_missing_include_dirs("${_sub}")
  endforeach()
endfunction()

cmake_language(DEFER DIRECTORY "${CMAKE_SOURCE_DIR}" CALL _sigcore_drop_missing_include_dirs "${CMAKE_SOURCE_DIR}")
