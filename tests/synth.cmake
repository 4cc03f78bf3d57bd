voca_add_test(test_synth SOURCES test_synth.cpp LIBS voca_synth TIMEOUT 120)
# Runs the `voca synth` command and reads its output back with the dataset, calibration,
# image and trajectory readers. Its fisheye case renders with two threads: under TSan, the renderer's
# threads are checked there, as the other threaded tests render their input with Release
# (VOCA_TEST_SYNTH, tools/test.sh).
voca_add_test(test_synth_e2e SOURCES test_synth_e2e.cpp
              LIBS voca_synth voca_pipeline_synth voca_formats_dataset voca_formats_calib voca_formats_image
                   voca_formats_trajectory LABELS e2e TIMEOUT 600
              THREAD_CASES "*TUM-VI fisheye*")
add_dependencies(test_synth_e2e voca)
# The accuracy evaluation set's builder (a Python tool): its choice of window, on known answers.
add_test(NAME test_make_eval_set COMMAND python3 ${CMAKE_CURRENT_SOURCE_DIR}/test_make_eval_set.py)
set_tests_properties(test_make_eval_set PROPERTIES LABELS tools)
voca_test_timeout(test_make_eval_set 60)
