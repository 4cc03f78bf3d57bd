# The evaluation harness (`voca bench suite` / `collect`): suite files, plans and tables without running
# anything; then the harness end to end through the `voca` binary, and the shipped default suite.
voca_add_test(test_harness SOURCES test_harness.cpp LIBS voca_harness LABELS asan)
