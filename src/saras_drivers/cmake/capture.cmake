# Build rules of the C++ stereo endoscope capture; included from CMakeLists.txt.
#   saras_drivers_capture_core     ROS-agnostic core: source strings (V4L2 / GStreamer / file), Decklink
#                                  pipeline, capture stamps, stereo pairing by time, back-off, health,
#                                  one capture thread per eye (OpenCV cv::VideoCapture)
#   saras_drivers_capture_nodelet  nodelet saras_drivers/StereoCapture (nodelet_plugins.xml) and its
#                                  parameter reading (saras_common::Params); as a node:
#                                  `nodelet standalone saras_drivers/StereoCapture`
find_package(OpenCV REQUIRED COMPONENTS core imgcodecs videoio)
find_package(Threads REQUIRED)
find_package(PkgConfig REQUIRED)
# GStreamer itself: checkPipeline() parses a pipeline before OpenCV opens it (eye_capture.h)
pkg_check_modules(GSTREAMER REQUIRED gstreamer-1.0)

add_library(${PROJECT_NAME}_capture_core
  src/capture/capture_core.cpp
  src/capture/eye_capture.cpp)
target_include_directories(${PROJECT_NAME}_capture_core PUBLIC include)
target_include_directories(${PROJECT_NAME}_capture_core SYSTEM PRIVATE ${OpenCV_INCLUDE_DIRS} ${GSTREAMER_INCLUDE_DIRS})
target_link_libraries(${PROJECT_NAME}_capture_core ${OpenCV_LIBRARIES} ${GSTREAMER_LIBRARIES} Threads::Threads)
target_compile_options(${PROJECT_NAME}_capture_core PRIVATE -Wall -Wextra)

add_library(${PROJECT_NAME}_capture_nodelet
  src/capture/capture_params.cpp
  src/capture/stereo_capture_nodelet.cpp)
target_include_directories(${PROJECT_NAME}_capture_nodelet SYSTEM PRIVATE ${catkin_INCLUDE_DIRS} ${OpenCV_INCLUDE_DIRS})
target_link_libraries(${PROJECT_NAME}_capture_nodelet ${PROJECT_NAME}_capture_core ${catkin_LIBRARIES})
target_compile_options(${PROJECT_NAME}_capture_nodelet PRIVATE -Wall -Wextra)
add_dependencies(${PROJECT_NAME}_capture_nodelet ${catkin_EXPORTED_TARGETS})

install(TARGETS ${PROJECT_NAME}_capture_core ${PROJECT_NAME}_capture_nodelet
  ARCHIVE DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  LIBRARY DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  RUNTIME DESTINATION ${CATKIN_GLOBAL_BIN_DESTINATION})
install(DIRECTORY include/${PROJECT_NAME}/
  DESTINATION ${CATKIN_PACKAGE_INCLUDE_DESTINATION}
  FILES_MATCHING PATTERN "capture_*.h" PATTERN "eye_capture.h")

if(CATKIN_ENABLE_TESTING)
  # core tests; test_eye_capture.cpp runs GStreamer videotestsrc pipelines (gstreamer1.0-plugins-base)
  catkin_add_gtest(${PROJECT_NAME}_capture_test
    test/capture/test_capture_core.cpp
    test/capture/test_capture_params.cpp
    test/capture/test_eye_capture.cpp
    src/capture/capture_params.cpp)
  target_include_directories(${PROJECT_NAME}_capture_test SYSTEM PRIVATE ${catkin_INCLUDE_DIRS} ${OpenCV_INCLUDE_DIRS})
  target_link_libraries(${PROJECT_NAME}_capture_test ${PROJECT_NAME}_capture_core ${catkin_LIBRARIES})
endif()
