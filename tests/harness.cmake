# The evaluation harness (`voca bench suite` / `collect`): suite files, plans and tables without running
# anything; then the harness end to end through the `voca` binary, and the shipped default suite.
voca_add_test(test_harness SOURCES test_harness.cpp LIBS voca_harness LABELS asan)
voca_add_test(test_bench_suite_e2e SOURCES test_bench_suite_e2e.cpp LIBS nlohmann_json::nlohmann_json LABELS e2e
              TIMEOUT 900)
target_compile_definitions(test_bench_suite_e2e PRIVATE VOCA_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
add_dependencies(test_bench_suite_e2e voca)
# The plots of a suite (tools/plot_suite.py) on a hand-made suite folder; needs python3-matplotlib.
# Debian's interpreter first: tools/setup.sh installs matplotlib for it, and a python3 earlier on PATH
# (pyenv, a virtualenv) may not have it.
find_program(VOCA_SYSTEM_PYTHON3 python3 PATHS /usr/bin NO_DEFAULT_PATH)
if(NOT VOCA_SYSTEM_PYTHON3)
  set(VOCA_SYSTEM_PYTHON3 python3)
endif()
add_test(NAME test_plot_suite COMMAND ${VOCA_SYSTEM_PYTHON3} ${CMAKE_CURRENT_SOURCE_DIR}/test_plot_suite.py)
set_tests_properties(test_plot_suite PROPERTIES LABELS tools SKIP_RETURN_CODE 77)
voca_test_timeout(test_plot_suite 120)
# The benchmarks' cached default sequence, rendered and encoded for real (1 s).
voca_add_test(test_bench_sequence_e2e SOURCES test_bench_sequence_e2e.cpp LIBS voca_harness voca_formats_dataset
              LABELS e2e TIMEOUT 600)
