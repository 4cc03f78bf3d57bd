# The library API as a program uses it: pushed H.264 and gray frames, bad input through it, the
# on-device encode path, pushing and polling from two threads, stopping from the destructor.
voca_add_test(test_api SOURCES test_api.cpp LIBS voca_rt_static voca_drivers_encode LABELS e2e TIMEOUT 300 THREADS)
