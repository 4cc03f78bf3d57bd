voca_add_test(test_synth SOURCES test_synth.cpp LIBS voca_synth TIMEOUT 120)
