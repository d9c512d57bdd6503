# drape_add_test(NAME name SOURCES a.cpp ... LIBS lib ... LABELS unit|slow [GUI] [SOLVER] [TIMEOUT s])
# One Qt Test executable per test file. GUI tests run under xvfb-run when there is
# no display, with Mesa's software OpenGL.
# The malloc settings of the `drape` command (below), for every test entry; a
# second entry of the same executable (tests/capture) sets them from here too.
set(DRAPE_TEST_MALLOC_ENV "GLIBC_TUNABLES=glibc.malloc.mmap_threshold=268435456:glibc.malloc.trim_threshold=536870912")

function(drape_add_test)
  cmake_parse_arguments(T "GUI;SOLVER" "NAME;TIMEOUT" "SOURCES;LIBS;LABELS;SANITIZE_FUNCTIONS" ${ARGN})
  # The sanitizer build runs the unit tests only: slow tests are not built there.
  if(DRAPE_SANITIZE AND T_LABELS AND NOT "unit" IN_LIST T_LABELS)
    return()
  endif()
  # SOLVER: a test of the solver's numerics (forces, drapes, fits, sensitivities)
  # on inputs the test makes itself. The sanitizer pass of CI builds the tests of
  # what reads outside input (records, photos, presets, meshes, the library, the
  # CLI with scripts/bad-inputs.sh, which drives the solver too) and leaves these
  # to the full pass (DRAPE_SANITIZE_SOLVER=ON, scripts/test.sh all): decision 0015.
  if(DRAPE_SANITIZE AND T_SOLVER AND NOT DRAPE_SANITIZE_SOLVER)
    return()
  endif()
  find_package(Qt6 REQUIRED COMPONENTS Core Test)
  add_executable(${T_NAME} ${T_SOURCES})
  # A test without the `unit` label (the slow ones) is not part of `all`: the
  # target `slow_tests` builds them (scripts/test.sh all does), so the unit
  # run (CI) does not spend its two cores compiling what it will not run.
  if(T_LABELS AND NOT "unit" IN_LIST T_LABELS)
    set_target_properties(${T_NAME} PROPERTIES EXCLUDE_FROM_ALL ON)
    add_dependencies(slow_tests ${T_NAME}) # the target: CMakeLists.txt
  endif()
  set_target_properties(${T_NAME} PROPERTIES AUTOMOC ON)
  target_link_libraries(${T_NAME} PRIVATE Qt6::Test ${T_LIBS})
  target_compile_definitions(${T_NAME} PRIVATE
    DRAPE_SHARED_DIR="${DRAPE_SHARED_DIR}" DRAPE_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
  set_target_properties(${T_NAME} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/tests)
  drape_set_warnings(${T_NAME})
  # A test's own file is compiled at -O1 in an optimised build: the code under
  # test is in the libraries (-O3); -O3 on the test files cost a quarter of their
  # compile time for no run time (decision 0015).
  target_compile_options(${T_NAME} PRIVATE $<$<CONFIG:Release>:-O1>)
  if(T_GUI)
    add_test(NAME ${T_NAME} COMMAND ${PROJECT_SOURCE_DIR}/cmake/run-gui-test.sh $<TARGET_FILE:${T_NAME}>)
  else()
    # SANITIZE_FUNCTIONS: under the sanitizers (5-10x slower) a test that drives
    # hundreds of simulations runs only these Qt Test functions; the code they
    # reach is the same, the full test runs in the release build.
    if(DRAPE_SANITIZE AND T_SANITIZE_FUNCTIONS)
      add_test(NAME ${T_NAME} COMMAND ${T_NAME} ${T_SANITIZE_FUNCTIONS})
    else()
      add_test(NAME ${T_NAME} COMMAND ${T_NAME})
    endif()
  endif()
  if(NOT T_LABELS)
    set(T_LABELS unit)
  endif()
  if(NOT T_TIMEOUT)
    set(T_TIMEOUT 600)
  endif()
  # The malloc settings the `drape` command sets for itself (cli/main.cpp): the
  # tests run the same library code in-process, and glibc's default maps and
  # unmaps each large image buffer afresh (a quarter of a photo measurement in
  # page faults on a VM). ASan's allocator ignores them.
  # Qt Test's watchdog (5 minutes per test function by default) follows the
  # test's own TIMEOUT, so a loaded machine meets ctest's limit, not a hidden one.
  math(EXPR _qt_timeout_ms "${T_TIMEOUT} * 1000")
  set_tests_properties(${T_NAME} PROPERTIES LABELS "${T_LABELS}" TIMEOUT ${T_TIMEOUT}
    ENVIRONMENT "${DRAPE_TEST_MALLOC_ENV};QTEST_FUNCTION_TIMEOUT=${_qt_timeout_ms}")
endfunction()

# drape_add_slow_entry(TEST exe NAME entry FUNCTIONS f ... [GUI] [TIMEOUT s])
# A second ctest entry of a unit test's executable, label `slow`, that runs the
# named Qt Test functions with DRAPE_TEST_SLOW=1 in the environment. The test
# code skips its costly cases unless that variable is set (tests/slow_cases.hpp),
# so the unit entry keeps every function - a new one runs by default - and the
# slow entry adds the costly cases (scripts/test.sh all runs them).
function(drape_add_slow_entry)
  cmake_parse_arguments(S "GUI" "TEST;NAME;TIMEOUT" "FUNCTIONS" ${ARGN})
  if(DRAPE_SANITIZE OR NOT TARGET ${S_TEST})
    return()
  endif()
  if(NOT S_TIMEOUT)
    set(S_TIMEOUT 600)
  endif()
  math(EXPR _qt_timeout_ms "${S_TIMEOUT} * 1000")
  if(S_GUI)
    add_test(NAME ${S_NAME} COMMAND ${PROJECT_SOURCE_DIR}/cmake/run-gui-test.sh $<TARGET_FILE:${S_TEST}> ${S_FUNCTIONS})
  else()
    add_test(NAME ${S_NAME} COMMAND ${S_TEST} ${S_FUNCTIONS})
  endif()
  set_tests_properties(${S_NAME} PROPERTIES LABELS slow TIMEOUT ${S_TIMEOUT}
    ENVIRONMENT "DRAPE_TEST_SLOW=1;${DRAPE_TEST_MALLOC_ENV};QTEST_FUNCTION_TIMEOUT=${_qt_timeout_ms}")
endfunction()
