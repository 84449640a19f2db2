# Helper functions shared by libcore/, tools/ and tests/.

# mvtm_add_library(NAME SOURCES a.cpp ... PUBLIC_DEPS ... PRIVATE_DEPS ...)
# One static library per libcore module; headers are included as "module/header.h".
function(mvtm_add_library name)
  cmake_parse_arguments(A "" "" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(mvtm_${name} STATIC ${A_SOURCES})
  add_library(mvtm::${name} ALIAS mvtm_${name})
  target_include_directories(mvtm_${name} PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/libcore>)
  target_link_libraries(mvtm_${name} PUBLIC ${A_PUBLIC_DEPS} PRIVATE mvtm_flags ${A_PRIVATE_DEPS})
  set_target_properties(mvtm_${name} PROPERTIES POSITION_INDEPENDENT_CODE ON)
endfunction()

# mvtm_add_tool(NAME SOURCES main.cpp name.cpp DEPS ...)
# Builds tools/NAME as the executable NAME (output in build/bin/) with a library
# mvtm_tool_NAME of everything but main.cpp, so tests can call RunTool() directly.
function(mvtm_add_tool name)
  cmake_parse_arguments(A "" "" "SOURCES;DEPS" ${ARGN})
  set(lib_sources ${A_SOURCES})
  list(REMOVE_ITEM lib_sources main.cpp)
  add_library(mvtm_tool_${name} STATIC ${lib_sources})
  target_include_directories(mvtm_tool_${name} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR})
  target_link_libraries(mvtm_tool_${name} PUBLIC ${A_DEPS} PRIVATE mvtm_flags)
  add_executable(${name} main.cpp)
  target_link_libraries(${name} PRIVATE mvtm_tool_${name} mvtm_flags)
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/bin)
  add_dependencies(${name} mvtm_plugins)  # modules opened with dlopen (base/plugin.h)
  install(TARGETS ${name} RUNTIME DESTINATION bin)
  install(FILES ${PROJECT_SOURCE_DIR}/man/${name}.1 DESTINATION share/man/man1 OPTIONAL)
endfunction()

# mvtm_add_unit_test(NAME SOURCES ... DEPS ... [LABELS ...])
function(mvtm_add_unit_test name)
  cmake_parse_arguments(A "" "" "SOURCES;DEPS;LABELS" ${ARGN})
  add_executable(${name} ${A_SOURCES})
  target_link_libraries(${name} PRIVATE ${A_DEPS} GTest::gtest GTest::gtest_main mvtm_flags)
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR}/tests/unit)  # support/
  target_compile_definitions(${name} PRIVATE
    MVTM_SOURCE_DIR="${PROJECT_SOURCE_DIR}" MVTM_BINARY_DIR="${PROJECT_BINARY_DIR}")
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/tests)
  add_dependencies(${name} mvtm_plugins)
  add_test(NAME ${name} COMMAND ${name})
  set_tests_properties(${name} PROPERTIES LABELS "unit;${A_LABELS}"
    ENVIRONMENT "MVTM_BIN=${PROJECT_BINARY_DIR}/bin;MVTM_SOURCE=${PROJECT_SOURCE_DIR}")
endfunction()
