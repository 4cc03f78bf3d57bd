# Layer boundaries: no file in voca/ includes formats/, drivers/, pipeline/, tools/ or platform/,
# formats/ no drivers/, pipeline/ or tools/, drivers/ no pipeline/ or tools/, pipeline/ no tools/
# (tools/check_layers.sh), and the check itself fails on bad includes. Shell scripts on the host: kept out of the emulated cross run.
add_test(NAME test_layers COMMAND bash ${PROJECT_SOURCE_DIR}/tools/check_layers.sh ${PROJECT_SOURCE_DIR})
add_test(NAME test_check_layers COMMAND bash ${CMAKE_CURRENT_SOURCE_DIR}/test_check_layers.sh
                                        ${PROJECT_SOURCE_DIR}/tools/check_layers.sh)
set_tests_properties(test_layers test_check_layers PROPERTIES LABELS "unit;noemu")
