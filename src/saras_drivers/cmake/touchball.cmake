# Build rules of the C++ touchball component; included from CMakeLists.txt.
#   saras_drivers_touchball_core     ROS-agnostic core: protocol v2 decode/encode, HMAC-SHA256 tags
#                                    (OpenSSL libcrypto), key file, link validation, session handshake,
#                                    sequence, twist, watchdog deadline, force latch, UDP socket,
#                                    receive-thread hand-off and health report, Touch IK
#   saras_drivers_touchball_nodelet  nodelet saras_drivers/TouchballReceiver (nodelet_plugins.xml) and its
#                                    parameter reading (saras_common::Params); as a node:
#                                    `nodelet standalone saras_drivers/TouchballReceiver`
find_package(OpenSSL REQUIRED)

add_library(${PROJECT_NAME}_touchball_core
  src/touchball/touchball_auth.cpp
  src/touchball/touchball_kinematics.cpp
  src/touchball/touchball_link.cpp
  src/touchball/touchball_protocol.cpp
  src/touchball/touchball_receiver_core.cpp
  src/touchball/touchball_udp.cpp)
target_include_directories(${PROJECT_NAME}_touchball_core PUBLIC include)
target_include_directories(${PROJECT_NAME}_touchball_core SYSTEM PRIVATE ${EIGEN3_INCLUDE_DIRS} ${OPENSSL_INCLUDE_DIR})
target_link_libraries(${PROJECT_NAME}_touchball_core ${OPENSSL_CRYPTO_LIBRARY})
target_compile_options(${PROJECT_NAME}_touchball_core PRIVATE -Wall -Wextra)

add_library(${PROJECT_NAME}_touchball_nodelet
  src/touchball/touchball_receiver_nodelet.cpp
  src/touchball/touchball_receiver_params.cpp)
target_include_directories(${PROJECT_NAME}_touchball_nodelet SYSTEM PRIVATE ${catkin_INCLUDE_DIRS})
target_link_libraries(${PROJECT_NAME}_touchball_nodelet ${PROJECT_NAME}_touchball_core ${catkin_LIBRARIES})
target_compile_options(${PROJECT_NAME}_touchball_nodelet PRIVATE -Wall -Wextra)
add_dependencies(${PROJECT_NAME}_touchball_nodelet ${catkin_EXPORTED_TARGETS})

install(TARGETS ${PROJECT_NAME}_touchball_core ${PROJECT_NAME}_touchball_nodelet
  ARCHIVE DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  LIBRARY DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  RUNTIME DESTINATION ${CATKIN_GLOBAL_BIN_DESTINATION})
install(DIRECTORY include/${PROJECT_NAME}/
  DESTINATION ${CATKIN_PACKAGE_INCLUDE_DESTINATION}
  FILES_MATCHING PATTERN "touchball_*.h")

if(CATKIN_ENABLE_TESTING)
  # Touch kinematics table: joint values and handle poses computed by saras_description's
  # forward kinematics (the reference model, it generates the URDF); regenerate with
  # test/touchball/touch_fk_table.py (test/touchball/test_touch_fk_table.py checks it is current).
  catkin_add_gtest(${PROJECT_NAME}_touchball_test
    test/touchball/test_touchball_auth.cpp
    test/touchball/test_touchball_core.cpp
    test/touchball/test_touchball_kinematics.cpp
    test/touchball/test_touchball_receiver_core.cpp
    test/touchball/test_touchball_receiver_params.cpp
    test/touchball/test_touchball_udp.cpp
    src/touchball/touchball_receiver_params.cpp)
  target_include_directories(${PROJECT_NAME}_touchball_test SYSTEM PRIVATE ${EIGEN3_INCLUDE_DIRS} ${OPENSSL_INCLUDE_DIR}
    ${catkin_INCLUDE_DIRS})
  target_compile_definitions(${PROJECT_NAME}_touchball_test PRIVATE
    TOUCHBALL_TEST_DATA="${PROJECT_SOURCE_DIR}/test/touchball/data")
  # the parameter test reads through saras_common::Params from a map (no roscore); it needs roscpp's XmlRpc
  target_link_libraries(${PROJECT_NAME}_touchball_test ${PROJECT_NAME}_touchball_core ${OPENSSL_CRYPTO_LIBRARY}
    ${catkin_LIBRARIES})
endif()
