# saras_add_pytest(<dir> [NAME <name>] [ARGS "<pytest args>"])
#
# Registers the pytest suite found under <dir> (relative to the calling package) with catkin's
# run_tests, as catkin_add_nosetests does for nose: `catkin_make run_tests` (or
# `make -C build run_tests`) runs it, and its JUnit result lands in the package's test_results
# folder where catkin_test_results finds it. rostest nodes (test/rostest/) are not collected.
# Runs Debian's /usr/bin/python3 (a pyenv python3 on PATH cannot import the ROS modules).
function(saras_add_pytest dir)
  cmake_parse_arguments(_sp "" "NAME;ARGS" "" ${ARGN})
  if(NOT _sp_NAME)
    string(REPLACE "/" "_" _sp_NAME "${dir}")
  endif()
  set(_out ${CATKIN_TEST_RESULTS_DIR}/${PROJECT_NAME})
  set(_xml "pytest-${_sp_NAME}.xml")
  # catkin's run_tests.py runs each COMMAND entry as one shell command
  set(_mkdir "\"${CMAKE_COMMAND}\" -E make_directory ${_out}")
  set(_pytest "/usr/bin/python3 -m pytest -q -p no:cacheprovider --rootdir=${PROJECT_SOURCE_DIR}")
  set(_pytest "${_pytest} -o python_files=test_*.py --ignore-glob=*/rostest/* ${_sp_ARGS}")
  set(_pytest "${_pytest} --junitxml=${_out}/${_xml} ${PROJECT_SOURCE_DIR}/${dir}")
  catkin_run_tests_target("pytest" ${_sp_NAME} ${_xml}
    COMMAND ${_mkdir} ${_pytest}
    WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
endfunction()
