# ROS 2 over DDS without ROS: names and domains, the twist, the bytes on the wire against the IDL's
# layout (a known answer), and the sink's policy, ring and drain. Runs Cyclone DDS on loopback.
voca_add_test(test_ros2 SOURCES test_ros2.cpp test_ros2_sink.cpp LIBS voca_pipeline_sinks voca_drivers_ros2 voca_drivers_ros2_msgs
              TIMEOUT 120 THREADS)
# `voca run --ros2` against a DDS subscriber in the test: every message is its trajectory row.
voca_add_test(test_ros2_e2e SOURCES test_ros2_e2e.cpp LIBS voca_drivers_ros2_msgs nlohmann_json::nlohmann_json
              LABELS e2e TIMEOUT 600
              THREAD_CASES "*rendered sequence*")
add_dependencies(test_ros2_e2e voca)
