voca_add_test(test_trajectory SOURCES test_trajectory.cpp LIBS voca_trajectory fmt::fmt)
voca_add_test(test_trajectory_errors SOURCES test_trajectory_errors.cpp LIBS voca_trajectory LABELS asan)
