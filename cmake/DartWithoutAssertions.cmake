# DART compiled again from Debian's own source without assertions, for the physics.
#
# Debian builds libdart with CMAKE_BUILD_TYPE=None: NDEBUG stays undefined, so every Eigen
# index check and DART assert runs inside each physics step. The same source (the version
# installed, with Debian's patches; fetched by deploy/dart-source.sh into .deps/dart/<version>)
# built as DART's own Release build type builds it (-O3 -DNDEBUG), with Debian's hardening
# flags, computes the same numbers bit for bit and steps the demo's grasp about a third
# faster (docs/benchmarks.md, "Physics server"; a test compares the state digests).
#
# Everything still compiles and links against Debian's headers and libraries; only where the
# programs load libdart and libdart-collision-bullet from changes: a RUNPATH to this build's
# copies, which have Debian's sonames. A build step checks that the copy was configured with
# the features Debian's has (its config.hpp), since our code is compiled against Debian's.
#
#   skillbus_dart_without_assertions(<target>)  the programs linking <target> load the copy
#
# Off with -DSKILLBUS_DART_WITHOUT_ASSERTIONS=OFF, and with a sanitizer. Without the source
# (no network when deploy/setup.sh ran) the build warns and the physics runs on Debian's.

include(ExternalProject)

option(SKILLBUS_DART_WITHOUT_ASSERTIONS
       "load DART rebuilt from Debian's source with -DNDEBUG (deploy/dart-source.sh fetches it)" ON)
# (the libraries' folder, or empty when the programs load Debian's: read by the tests and benches)
set(SKILLBUS_DART_LIBRARY_DIR "" CACHE INTERNAL "where the programs load DART without assertions from")

if(SKILLBUS_DART_WITHOUT_ASSERTIONS AND NOT CMAKE_CXX_FLAGS MATCHES "-fsanitize")
  execute_process(COMMAND dpkg-query -W "-f=\${source:Version}" libdart-dev
                  OUTPUT_VARIABLE _dart_deb_version RESULT_VARIABLE _dart_query ERROR_QUIET)
  find_file(SKILLBUS_DART_CONFIG_HPP dart/config.hpp HINTS ${DART_INCLUDE_DIRS} NO_DEFAULT_PATH)
  set(_dart_deps ${PROJECT_SOURCE_DIR}/.deps/dart)
  string(REPLACE ":" "_" _dart_source "${_dart_deps}/${_dart_deb_version}")  # (as deploy/dart-source.sh names it)
  # Configure again when a source arrives (the folder changes) or Debian's DART is installed
  # again or upgraded (dpkg writes its packages' file lists anew; the files themselves keep
  # the package's dates): a copy of another version is never loaded beside Debian's headers.
  file(MAKE_DIRECTORY ${_dart_deps})
  file(GLOB _dart_dpkg_lists /var/lib/dpkg/info/libdart-dev.list /var/lib/dpkg/info/libdart-dev:*.list
       /var/lib/dpkg/info/libdart6.*.list /var/lib/dpkg/info/libdart-collision-bullet6.*.list)
  set_property(DIRECTORY ${PROJECT_SOURCE_DIR} APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS
               ${_dart_deps} ${SKILLBUS_DART_CONFIG_HPP} ${_dart_dpkg_lists})
  if(NOT SKILLBUS_DART_CONFIG_HPP)
    message(WARNING "DART without assertions: Debian's dart/config.hpp is not among DART's include "
                    "directories (${DART_INCLUDE_DIRS}): the physics runs on Debian's build of DART")
  elseif(NOT _dart_query EQUAL 0 OR _dart_deb_version STREQUAL "")
    message(WARNING "DART without assertions: libdart-dev's version is unknown (dpkg-query failed): "
                    "the physics runs on Debian's build of DART, with assertions")
  elseif(NOT EXISTS ${_dart_source}/CMakeLists.txt)
    message(WARNING "DART without assertions: no source of DART ${_dart_deb_version} in ${_dart_deps} "
                    "(deploy/dart-source.sh fetches it; deploy/setup.sh runs it): the physics runs on "
                    "Debian's build of DART, with assertions, its step about half as long again")
  else()
    # (a folder per version: another version's CMake cache would refuse the new source; an
    # epoch's colon would split the RUNPATH)
    string(REPLACE ":" "_" _dart_folder "${_dart_deb_version}")
    set(_dart_build ${CMAKE_BINARY_DIR}/dart-without-assertions/${_dart_folder})
    set(SKILLBUS_DART_LIBRARY_DIR ${_dart_build}/lib CACHE INTERNAL "where the programs load DART without assertions from")
    # DART's Release flags (-O3 -DNDEBUG) with Debian's hardening (dpkg-buildflags), without -g.
    # (Neither contracts nor reorders floating-point operations: the same numbers as -O2.)
    set(_dart_flags "-O3 -fstack-protector-strong -Wformat -Werror=format-security -Wdate-time -D_FORTIFY_SOURCE=2 -DNDEBUG")
    set(_dart_launcher)
    if(CCACHE_PROGRAM)
      set(_dart_launcher -DCMAKE_CXX_COMPILER_LAUNCHER=${CCACHE_PROGRAM} -DCMAKE_C_COMPILER_LAUNCHER=${CCACHE_PROGRAM})
    endif()
    ExternalProject_Add(dart_without_assertions
      SOURCE_DIR ${_dart_source}
      LIST_SEPARATOR |
      BINARY_DIR ${_dart_build}
      CMAKE_ARGS -DCMAKE_BUILD_TYPE=None "-DCMAKE_CXX_FLAGS=${_dart_flags}" -DCMAKE_INSTALL_PREFIX=/usr
                 "-DCMAKE_SHARED_LINKER_FLAGS=-Wl,-z,relro -Wl,-z,now"
                 -DBUILD_SHARED_LIBS=ON -DDART_SKIP_FLANN=ON -DDART_SKIP_PAGMO=ON -DDART_BUILD_GUI_OSG=OFF
                 # The libraries' RUNPATH names exactly their two folders (libdart's LCP solver,
                 # and libdart for the collision detector): CMake's build-tree RUNPATH ends in
                 # an empty entry, which the loader reads as the current directory.
                 -DCMAKE_BUILD_WITH_INSTALL_RPATH=ON
                 "-DCMAKE_INSTALL_RPATH=${_dart_build}/lib|${_dart_build}/dart/external/odelcpsolver"
                 ${_dart_launcher}
      # Only what the programs load in the step: libdart (and its LCP solver) and the Bullet
      # collision detector; the URDF reader and utilities stay Debian's.
      BUILD_COMMAND ${CMAKE_COMMAND} --build ${_dart_build} --target dart-collision-bullet --parallel 2
      INSTALL_COMMAND ""
      # (DART's own configure and build talk a lot: into log files, shown when a step fails)
      LOG_CONFIGURE TRUE LOG_BUILD TRUE LOG_OUTPUT_ON_FAILURE TRUE
      BUILD_BYPRODUCTS ${_dart_build}/lib/libdart.so.${DART_VERSION_MAJOR}.${DART_VERSION_MINOR}
                       ${_dart_build}/lib/libdart-collision-bullet.so.${DART_VERSION_MAJOR}.${DART_VERSION_MINOR})
    ExternalProject_Add_Step(dart_without_assertions same_features
      COMMAND ${CMAKE_COMMAND} -DBUILT=${_dart_build}/dart/config.hpp
              -DDEBIAN=${SKILLBUS_DART_CONFIG_HPP} -P ${PROJECT_SOURCE_DIR}/cmake/DartSameFeatures.cmake
      DEPENDEES configure DEPENDERS build)
  endif()
endif()

function(skillbus_dart_without_assertions target)
  if(SKILLBUS_DART_LIBRARY_DIR)
    add_dependencies(${target} dart_without_assertions)
    # (INTERFACE: the option reaches every program that links <target>)
    target_link_options(${target} INTERFACE "LINKER:-rpath,${SKILLBUS_DART_LIBRARY_DIR}")
  endif()
endfunction()
