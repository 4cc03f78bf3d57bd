voca_add_test(test_camera SOURCES test_camera.cpp LIBS voca_camera)
# Bad parameters and model names: also run under AddressSanitizer.
voca_add_test(test_camera_generic SOURCES test_camera_generic.cpp LIBS voca_camera LABELS asan)
