# Build rules of the stereo endoscope simulator; included from CMakeLists.txt.
#   saras_simulation_endoscope_core     ROS-free core: camera_info (image_geometry camera model), tissue /
#                                       bones (saras_collision's vertices file) / targets, ray-casting
#                                       renderer
#   saras_simulation_endoscope_sim      ROS-free frame logic: configuration, pose/stamp policy, health,
#                                       eye threads, stereo scene, outgoing messages
#   saras_simulation_endoscope_nodelet  nodelet saras_simulation/EndoscopeSim (nodelet_plugins.xml);
#                                       as a node: `nodelet standalone saras_simulation/EndoscopeSim`
#   endoscope_render                    CLI: one frame of the core to a PNG (tests, timing)
find_package(OpenCV REQUIRED COMPONENTS core imgproc imgcodecs calib3d aruco)
find_package(Threads REQUIRED)

set(SARAS_SIMULATION_ENDOSCOPE_CORE_SOURCES
  src/endoscope/endoscope_camera_info.cpp
  src/endoscope/endoscope_renderer.cpp
  src/endoscope/endoscope_renderer_boxes.cpp
  src/endoscope/endoscope_renderer_tissue.cpp
  src/endoscope/endoscope_scene.cpp)
# the core's ROS pieces: message types, image_geometry's camera model, camera_calibration_parsers
set(SARAS_SIMULATION_ENDOSCOPE_CORE_LIBRARIES ${OpenCV_LIBRARIES} ${saras_collision_LIBRARIES}
  ${image_geometry_LIBRARIES} ${camera_calibration_parsers_LIBRARIES})
add_library(${PROJECT_NAME}_endoscope_core ${SARAS_SIMULATION_ENDOSCOPE_CORE_SOURCES})
target_include_directories(${PROJECT_NAME}_endoscope_core PUBLIC include)
# saras_collision's forbidden-region vertices-file parser and box model come with catkin_INCLUDE_DIRS
target_include_directories(${PROJECT_NAME}_endoscope_core SYSTEM PRIVATE ${EIGEN3_INCLUDE_DIRS} ${OpenCV_INCLUDE_DIRS}
  ${catkin_INCLUDE_DIRS})
target_link_libraries(${PROJECT_NAME}_endoscope_core ${SARAS_SIMULATION_ENDOSCOPE_CORE_LIBRARIES})
add_dependencies(${PROJECT_NAME}_endoscope_core ${catkin_EXPORTED_TARGETS})
target_compile_options(${PROJECT_NAME}_endoscope_core PRIVATE -Wall -Wextra -O3)

# ROS-free frame logic of the simulator (no node handle): configuration (saras_common::Params),
# pose/stamp policy, health, eye threads, stereo scene and outgoing messages
add_library(${PROJECT_NAME}_endoscope_sim
  src/endoscope/endoscope_sim_config.cpp
  src/endoscope/endoscope_sim_core.cpp
  src/endoscope/endoscope_stereo.cpp)
target_include_directories(${PROJECT_NAME}_endoscope_sim PUBLIC include)
target_include_directories(${PROJECT_NAME}_endoscope_sim SYSTEM PRIVATE ${catkin_INCLUDE_DIRS} ${EIGEN3_INCLUDE_DIRS}
  ${OpenCV_INCLUDE_DIRS})
# catkin_LIBRARIES: saras_visual_feedback's JpegEncoder (the recorded JPEG streams, libjpeg-turbo)
target_link_libraries(${PROJECT_NAME}_endoscope_sim ${PROJECT_NAME}_endoscope_core ${catkin_LIBRARIES}
  ${OpenCV_LIBRARIES} Threads::Threads)
target_compile_options(${PROJECT_NAME}_endoscope_sim PRIVATE -Wall -Wextra)
add_dependencies(${PROJECT_NAME}_endoscope_sim ${catkin_EXPORTED_TARGETS})

add_library(${PROJECT_NAME}_endoscope_nodelet src/endoscope/endoscope_sim_nodelet.cpp)
target_include_directories(${PROJECT_NAME}_endoscope_nodelet SYSTEM PRIVATE ${catkin_INCLUDE_DIRS} ${EIGEN3_INCLUDE_DIRS} ${OpenCV_INCLUDE_DIRS})
target_link_libraries(${PROJECT_NAME}_endoscope_nodelet ${PROJECT_NAME}_endoscope_sim ${catkin_LIBRARIES})
target_compile_options(${PROJECT_NAME}_endoscope_nodelet PRIVATE -Wall -Wextra)
add_dependencies(${PROJECT_NAME}_endoscope_nodelet ${catkin_EXPORTED_TARGETS})

add_executable(${PROJECT_NAME}_endoscope_render src/endoscope/endoscope_render_cli.cpp)
set_target_properties(${PROJECT_NAME}_endoscope_render PROPERTIES OUTPUT_NAME endoscope_render)
target_include_directories(${PROJECT_NAME}_endoscope_render SYSTEM PRIVATE ${EIGEN3_INCLUDE_DIRS} ${OpenCV_INCLUDE_DIRS}
  ${catkin_INCLUDE_DIRS})
target_link_libraries(${PROJECT_NAME}_endoscope_render ${PROJECT_NAME}_endoscope_core ${OpenCV_LIBRARIES})

install(TARGETS ${PROJECT_NAME}_endoscope_core ${PROJECT_NAME}_endoscope_nodelet ${PROJECT_NAME}_endoscope_sim
  ARCHIVE DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  LIBRARY DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  RUNTIME DESTINATION ${CATKIN_GLOBAL_BIN_DESTINATION})
install(TARGETS ${PROJECT_NAME}_endoscope_render
  RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
install(DIRECTORY include/${PROJECT_NAME}/
  DESTINATION ${CATKIN_PACKAGE_INCLUDE_DESTINATION})

if(CATKIN_ENABLE_TESTING)
  catkin_add_gtest(${PROJECT_NAME}_endoscope_test test/endoscope/test_endoscope_core.cpp)
  target_compile_definitions(${PROJECT_NAME}_endoscope_test PRIVATE
    ENDOSCOPE_TEST_CONFIG_DIR="${PROJECT_SOURCE_DIR}/config")
  target_include_directories(${PROJECT_NAME}_endoscope_test SYSTEM PRIVATE ${EIGEN3_INCLUDE_DIRS} ${OpenCV_INCLUDE_DIRS}
    ${catkin_INCLUDE_DIRS})
  target_link_libraries(${PROJECT_NAME}_endoscope_test ${PROJECT_NAME}_endoscope_core ${OpenCV_LIBRARIES})
  catkin_add_gtest(${PROJECT_NAME}_endoscope_sim_test test/endoscope/test_endoscope_sim.cpp)
  target_compile_definitions(${PROJECT_NAME}_endoscope_sim_test PRIVATE
    ENDOSCOPE_TEST_CONFIG_DIR="${PROJECT_SOURCE_DIR}/config")
  target_include_directories(${PROJECT_NAME}_endoscope_sim_test SYSTEM PRIVATE ${EIGEN3_INCLUDE_DIRS}
    ${OpenCV_INCLUDE_DIRS} ${catkin_INCLUDE_DIRS})
  target_link_libraries(${PROJECT_NAME}_endoscope_sim_test ${PROJECT_NAME}_endoscope_sim ${OpenCV_LIBRARIES})
  # The renderer's hot loops are multiversioned (GCC target_clones, clone chosen at load time); the
  # same tests against the baseline x86-64 code alone, so that both code paths are tested on any machine.
  catkin_add_gtest(${PROJECT_NAME}_endoscope_test_baseline test/endoscope/test_endoscope_core.cpp
    ${SARAS_SIMULATION_ENDOSCOPE_CORE_SOURCES})
  target_compile_definitions(${PROJECT_NAME}_endoscope_test_baseline PRIVATE SARAS_ENDOSCOPE_NO_MULTIVERSION
    ENDOSCOPE_TEST_CONFIG_DIR="${PROJECT_SOURCE_DIR}/config")
  target_compile_options(${PROJECT_NAME}_endoscope_test_baseline PRIVATE -O3)
  target_include_directories(${PROJECT_NAME}_endoscope_test_baseline PRIVATE include)
  target_include_directories(${PROJECT_NAME}_endoscope_test_baseline SYSTEM PRIVATE ${EIGEN3_INCLUDE_DIRS}
    ${OpenCV_INCLUDE_DIRS} ${catkin_INCLUDE_DIRS})
  target_link_libraries(${PROJECT_NAME}_endoscope_test_baseline ${SARAS_SIMULATION_ENDOSCOPE_CORE_LIBRARIES})
endif()
