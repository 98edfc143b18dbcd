# Build rules of the C++ endoscope component (owned by its engineer); included from CMakeLists.txt.
