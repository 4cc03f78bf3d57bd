voca_add_test(test_eval SOURCES test_eval.cpp LIBS voca_eval voca_formats_eval)
voca_add_test(test_eval_evo SOURCES test_eval_evo.cpp LIBS voca_eval voca_formats_calib voca_formats_trajectory LABELS e2e)
voca_add_test(test_results_table SOURCES test_results_table.cpp LIBS voca_eval)
