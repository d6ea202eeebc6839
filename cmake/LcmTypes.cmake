# lcm_generate(TARGET name PACKAGE pkg FILES a.lcm b.lcm)
# Generates C++ headers with lcm-gen at build time into an INTERFACE library `name`,
# and, when a JDK and lcm.jar are present, `name_java` -> ${CMAKE_BINARY_DIR}/share/java/<name>.jar
# so that lcm-spy can decode the messages.
set(LANEMAP_LCM_GUARD ${CMAKE_CURRENT_LIST_DIR}/lcm_guard.cmake)
function(lcm_generate)
  cmake_parse_arguments(ARG "" "TARGET;PACKAGE" "FILES" ${ARGN})
  set(cpp_dir ${CMAKE_BINARY_DIR}/lcmtypes/cpp)
  set(headers "")
  foreach(f ${ARG_FILES})
    get_filename_component(name ${f} NAME_WE)
    list(APPEND headers ${cpp_dir}/${ARG_PACKAGE}/${name}.hpp)
  endforeach()
  add_custom_command(
    OUTPUT ${headers}
    COMMAND ${CMAKE_COMMAND} -E make_directory ${cpp_dir}
    COMMAND ${LCM_GEN} --cpp --cpp-hpath ${cpp_dir} ${ARG_FILES}
    # Hostile sizes make decode() fail instead of throwing or allocating gigabytes (issue 18).
    COMMAND ${CMAKE_COMMAND} -DDIR=${cpp_dir}/${ARG_PACKAGE} -P ${LANEMAP_LCM_GUARD}
    DEPENDS ${ARG_FILES} ${LANEMAP_LCM_GUARD}
    WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}
    COMMENT "lcm-gen --cpp ${ARG_PACKAGE}")
  add_custom_target(${ARG_TARGET}_gen DEPENDS ${headers})
  add_library(${ARG_TARGET} INTERFACE)
  add_dependencies(${ARG_TARGET} ${ARG_TARGET}_gen)
  target_include_directories(${ARG_TARGET} INTERFACE ${cpp_dir})
  target_link_libraries(${ARG_TARGET} INTERFACE PkgConfig::LCM)

  set(lcm_jar /usr/share/java/lcm.jar)
  if(Java_JAVAC_EXECUTABLE AND Java_JAR_EXECUTABLE AND EXISTS ${lcm_jar})
    set(jar ${CMAKE_BINARY_DIR}/share/java/${ARG_TARGET}.jar)
    add_custom_command(
      OUTPUT ${jar}
      COMMAND ${CMAKE_SOURCE_DIR}/cmake/lcm_java_jar.sh ${LCM_GEN} ${Java_JAVAC_EXECUTABLE}
              ${Java_JAR_EXECUTABLE} ${lcm_jar} ${CMAKE_BINARY_DIR}/lcmtypes/java ${jar} ${ARG_FILES}
      DEPENDS ${ARG_FILES} ${CMAKE_SOURCE_DIR}/cmake/lcm_java_jar.sh
      WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}
      COMMENT "lcm-gen --java ${ARG_PACKAGE} -> ${jar}")
    add_custom_target(${ARG_TARGET}_java ALL DEPENDS ${jar})
  endif()
endfunction()
