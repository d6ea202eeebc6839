# Conventions that let modules be added without editing a central list:
#   processes/<name>/main.cc, drivers/<name>/main.cc  -> build/bin/lanemap-<name with - for _>
#   tools/<name>.cc                                    -> build/bin/lanemap-<name>
#   tests/<module>/<name>_test.cc                      -> one GoogleTest binary each, run by ctest

# Every lanemap-* program is installed into bin/ (`cmake --install`, the Debian package), except
# the benchmarks (lanemap-bench-*), which read the source tree's data.
function(lanemap_executable name)
  cmake_parse_arguments(ARG "" "" "SOURCES;LIBS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS})
  if(NOT name MATCHES "^lanemap-bench-")
    install(TARGETS ${name} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  endif()
endfunction()

# lanemap_main_dirs(<folder> <libs...>): one executable per <folder>/<name>/main.cc (+ its other .cc)
function(lanemap_main_dirs folder)
  file(GLOB mains CONFIGURE_DEPENDS ${folder}/*/main.cc)
  foreach(m ${mains})
    get_filename_component(dir ${m} DIRECTORY)
    get_filename_component(name ${dir} NAME)
    string(REPLACE "_" "-" exe "lanemap-${name}")
    file(GLOB srcs CONFIGURE_DEPENDS ${dir}/*.cc)
    lanemap_executable(${exe} SOURCES ${srcs} LIBS ${ARGN})
  endforeach()
endfunction()
