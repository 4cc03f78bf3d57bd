voca_add_test(test_frontend SOURCES test_frontend.cpp LIBS voca_frontend Threads::Threads)
voca_add_test(test_frontend_alloc SOURCES test_frontend_alloc.cpp LIBS voca_frontend)
voca_add_test(test_frontend_config SOURCES test_frontend_config.cpp LIBS voca_formats_config LABELS asan)
target_compile_definitions(test_frontend_config PRIVATE VOCA_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
voca_add_test(test_frontend_e2e SOURCES test_frontend_e2e.cpp
  LIBS voca_frontend voca_formats_config voca_synth voca_formats_calib voca_formats_image voca_formats_dataset voca_drivers_encode
       voca_drivers_encode_dataset voca_drivers_decode
  LABELS e2e TIMEOUT 600)
target_compile_definitions(test_frontend_e2e PRIVATE VOCA_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
voca_add_test(test_patch_kernels SOURCES test_patch_kernels.cpp LIBS voca_frontend)
