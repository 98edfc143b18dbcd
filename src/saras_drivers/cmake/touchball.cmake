# Build rules of the C++ touchball component (owned by its engineer); included from CMakeLists.txt.
#   saras_drivers_touchball_core     ROS-agnostic core: protocol v1 decode/encode, link validation,
#                                    sequence/resync, twist, watchdog deadline, force latch, Touch IK
#   saras_drivers_touchball_nodelet  nodelet saras_drivers/TouchballReceiver (nodelet_plugins.xml)
#   touchball_receiver               thin node executable that loads the nodelet in-process
find_package(ZLIB REQUIRED)

add_library(${PROJECT_NAME}_touchball_core
  src/touchball/touchball_kinematics.cpp
  src/touchball/touchball_link.cpp
  src/touchball/touchball_protocol.cpp)
target_include_directories(${PROJECT_NAME}_touchball_core PUBLIC include)
target_include_directories(${PROJECT_NAME}_touchball_core SYSTEM PRIVATE ${EIGEN3_INCLUDE_DIRS} ${ZLIB_INCLUDE_DIRS})
target_link_libraries(${PROJECT_NAME}_touchball_core ${ZLIB_LIBRARIES})
target_compile_options(${PROJECT_NAME}_touchball_core PRIVATE -Wall -Wextra)

add_library(${PROJECT_NAME}_touchball_nodelet src/touchball/touchball_receiver_nodelet.cpp)
target_include_directories(${PROJECT_NAME}_touchball_nodelet SYSTEM PRIVATE ${catkin_INCLUDE_DIRS})
target_link_libraries(${PROJECT_NAME}_touchball_nodelet ${PROJECT_NAME}_touchball_core ${catkin_LIBRARIES})
target_compile_options(${PROJECT_NAME}_touchball_nodelet PRIVATE -Wall -Wextra)
add_dependencies(${PROJECT_NAME}_touchball_nodelet ${catkin_EXPORTED_TARGETS})

add_executable(${PROJECT_NAME}_touchball_receiver src/nodelet_node_main.cpp)
set_target_properties(${PROJECT_NAME}_touchball_receiver PROPERTIES OUTPUT_NAME touchball_receiver)
target_compile_definitions(${PROJECT_NAME}_touchball_receiver PRIVATE SARAS_NODE_NAME="touchball_receiver"
  SARAS_NODELET_TYPE="${PROJECT_NAME}/TouchballReceiver" SARAS_NODE_WHAT="the Touchball receiver")
target_include_directories(${PROJECT_NAME}_touchball_receiver SYSTEM PRIVATE ${catkin_INCLUDE_DIRS})
target_link_libraries(${PROJECT_NAME}_touchball_receiver ${catkin_LIBRARIES})
# the executable loads the nodelet through pluginlib: build it first
add_dependencies(${PROJECT_NAME}_touchball_receiver ${PROJECT_NAME}_touchball_nodelet)

install(TARGETS ${PROJECT_NAME}_touchball_core ${PROJECT_NAME}_touchball_nodelet
  ARCHIVE DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  LIBRARY DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  RUNTIME DESTINATION ${CATKIN_GLOBAL_BIN_DESTINATION})
install(TARGETS ${PROJECT_NAME}_touchball_receiver
  RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
install(DIRECTORY include/${PROJECT_NAME}/
  DESTINATION ${CATKIN_PACKAGE_INCLUDE_DESTINATION}
  FILES_MATCHING PATTERN "touchball_*.h")

if(CATKIN_ENABLE_TESTING)
  catkin_add_gtest(${PROJECT_NAME}_touchball_test test/touchball/test_touchball_core.cpp)
  target_include_directories(${PROJECT_NAME}_touchball_test SYSTEM PRIVATE ${EIGEN3_INCLUDE_DIRS} ${ZLIB_INCLUDE_DIRS})
  target_link_libraries(${PROJECT_NAME}_touchball_test ${PROJECT_NAME}_touchball_core ${ZLIB_LIBRARIES})
endif()
