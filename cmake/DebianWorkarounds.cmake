# Debian 12's OpenImageIO CMake config lists /usr/include/opencv4 (OpenCV is an
# optional dependency it was built with) among its include directories even when
# libopencv-dev is not installed, which makes CMake refuse the target. Drop the
# include directories that do not exist instead of pulling in OpenCV.
function(modestack_drop_missing_include_dirs target)
  if(NOT TARGET ${target})
    return()
  endif()
  get_target_property(dirs ${target} INTERFACE_INCLUDE_DIRECTORIES)
  if(NOT dirs)
    return()
  endif()
  set(kept "")
  foreach(dir IN LISTS dirs)
    if(dir MATCHES "^\\$<" OR EXISTS "${dir}")
      list(APPEND kept "${dir}")
    endif()
  endforeach()
  set_target_properties(${target} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${kept}")
endfunction()

modestack_drop_missing_include_dirs(OpenImageIO::OpenImageIO)
modestack_drop_missing_include_dirs(OpenImageIO::OpenImageIO_Util)
