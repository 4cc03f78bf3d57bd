voca_add_test(test_frontend SOURCES test_frontend.cpp LIBS voca_frontend)
