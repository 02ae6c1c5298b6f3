# The two CMake steps every interface package of this workspace shares (tumble_ros_interfaces and
# the vendored tf2_msgs): include() it after find_package(rosidl_default_generators).

# Workaround for ROS 2 Jazzy installed from the PyPI wheels (see docs/setup.md, "Setup details").
# The wheels' exported CMake targets (<pkg>::<pkg>__rosidl_generator_py, and possibly others) carry
# include directories of the machine that built the wheels
# (/opt/python/cp311-cp311/include/python3.11, its numpy include dir). CMake refuses, at generate
# time, an imported target whose INTERFACE_INCLUDE_DIRECTORIES names a path that does not exist.
# This drops such paths from every imported target of this directory. On a real ROS install every
# path exists, so this is a no-op there. Call it after the find_package() calls and again after
# rosidl_generate_interfaces(), which find_package()s more packages (service_msgs, ...).
function(tumble_ros_drop_missing_include_dirs)
  get_property(_targets DIRECTORY PROPERTY IMPORTED_TARGETS)
  foreach(_target IN LISTS _targets)
    get_target_property(_dirs ${_target} INTERFACE_INCLUDE_DIRECTORIES)
    if(NOT _dirs)
      continue()
    endif()
    set(_kept "")
    set(_dropped "")
    foreach(_dir IN LISTS _dirs)
      # Keep generator expressions (evaluated later) and paths that exist.
      if(_dir MATCHES "\\$<" OR EXISTS "${_dir}")
        list(APPEND _kept "${_dir}")
      else()
        list(APPEND _dropped "${_dir}")
      endif()
    endforeach()
    if(_dropped)
      message(STATUS "${_target}: dropping missing include dirs: ${_dropped}")
      set_property(TARGET ${_target} PROPERTY INTERFACE_INCLUDE_DIRECTORIES "${_kept}")
    endif()
  endforeach()
endfunction()

# Only the generators a Python package uses: the C structures, their typesupports (Fast DDS's and
# the introspection one, behind rosidl_typesupport_c) and the Python bindings over them. Every
# generator found registers itself (rosidl_default_generators, and geometry_msgs' dependencies,
# find the C++ ones too); the C++ structures and their three typesupports are dropped here unless
# ${option} is ON: no C++ code uses these interfaces, and compiling them was a third of an
# interface package's build CPU (docs/setup.md, "Setup details"). A macro: it sets the
# generator list in the caller's scope, where rosidl_generate_interfaces() reads it.
macro(tumble_ros_python_generators_only option)
  if(NOT ${option})
    set(_tumble_ros_generators "")
    foreach(_extension IN LISTS AMENT_EXTENSIONS_rosidl_generate_idl_interfaces)
      string(REGEX REPLACE ":.*" "" _package "${_extension}")
      if(NOT _package MATCHES "_cpp$")
        list(APPEND _tumble_ros_generators "${_extension}")
      endif()
    endforeach()
    set(AMENT_EXTENSIONS_rosidl_generate_idl_interfaces "${_tumble_ros_generators}")
  endif()
endmacro()
