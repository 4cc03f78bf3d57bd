# PNG reading and writing; bad files are checked under AddressSanitizer too.
voca_add_test(test_image SOURCES test_image.cpp LIBS voca_formats_image PNG::PNG LABELS asan)
