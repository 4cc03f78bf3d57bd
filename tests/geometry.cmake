voca_add_test(test_geometry SOURCES test_geometry.cpp LIBS voca_geometry)
