voca_add_test(test_detector SOURCES test_detector.cpp LIBS voca_frontend)
