# ROS 2 over DDS without ROS: names and domains, the twist, and the bytes on the wire against the
# IDL's layout (a known answer). Runs Cyclone DDS on loopback.
voca_add_test(test_ros2 SOURCES test_ros2.cpp LIBS voca_drivers_ros2 voca_drivers_ros2_msgs TIMEOUT 120)
