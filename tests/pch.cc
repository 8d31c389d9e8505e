// Hosts the precompiled headers the test programs reuse (tests/CMakeLists.txt); no tests.
