voca_add_test(test_decode SOURCES test_decode.cpp LIBS voca_drivers_decode voca_drivers_encode)
voca_add_test(test_decode_bad SOURCES test_decode_bad.cpp LIBS voca_drivers_decode voca_drivers_encode
              voca_drivers_dataset LABELS asan)
