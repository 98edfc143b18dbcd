# Build rules of the C++ touchball component (owned by its engineer); included from CMakeLists.txt.
