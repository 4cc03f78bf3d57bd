# The example program of examples/odometry built against the build tree's libvoca-rt.so: its TUM rows
# must be byte for byte those of `voca run --out` on the same video folder. (tools/check_install.sh
# builds the same program against an installed tree and the Debian packages.)
add_executable(voca_example_odometry ${PROJECT_SOURCE_DIR}/examples/odometry/main.cpp)
target_link_libraries(voca_example_odometry PRIVATE voca_rt)
voca_target_defaults(voca_example_odometry)
add_test(NAME test_example_odometry
         COMMAND bash ${CMAKE_CURRENT_SOURCE_DIR}/test_example_odometry.sh $<TARGET_FILE:voca_example_odometry>
                 $<TARGET_FILE:voca> ${PROJECT_SOURCE_DIR}/../shared/data)
set_tests_properties(test_example_odometry PROPERTIES LABELS e2e SKIP_RETURN_CODE 77)
voca_test_timeout(test_example_odometry 300)
