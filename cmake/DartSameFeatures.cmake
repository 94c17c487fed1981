# cmake -DBUILT=<config.hpp of the rebuilt DART> -DDEBIAN=<Debian's dart/config.hpp> -P DartSameFeatures.cmake
#
# Our programs are compiled against Debian's DART headers and load the rebuilt library
# (cmake/DartWithoutAssertions.cmake): both must have been configured with the same version
# and the same optional parts, or classes could differ in layout between the two. Compares
# the defines of config.hpp that say so; the paths and the optimizer plug-ins (separate
# libraries we do not build) may differ.
foreach(file BUILT DEBIAN)
  if(NOT EXISTS "${${file}}")
    message(FATAL_ERROR "DART without assertions: ${${file}} is missing")
  endif()
  file(STRINGS "${${file}}" _lines
       REGEX "^#define (DART_(MAJOR|MINOR|PATCH)_VERSION|HAVE_(BULLET|ODE|OCTOMAP)|DART_ENABLE_SIMD|ASSIMP_[A-Z_]+) ")
  set(_${file} "${_lines}")
endforeach()
if(NOT _BUILT STREQUAL _DEBIAN)
  message(FATAL_ERROR "DART without assertions: the rebuilt DART (${BUILT}) was configured unlike Debian's "
                      "(${DEBIAN}):\n  rebuilt: ${_BUILT}\n  Debian:  ${_DEBIAN}\n"
                      "Install what it lacks, or configure with -DSKILLBUS_DART_WITHOUT_ASSERTIONS=OFF")
endif()
list(LENGTH _BUILT _n)
message(STATUS "DART without assertions: configured as Debian's (${_n} features and version defines alike)")
