voca_add_test(test_motion SOURCES test_motion.cpp LIBS voca_motion)
