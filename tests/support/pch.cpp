// The translation unit that builds the unit tests' precompiled header
// (test_pch in tests/CMakeLists.txt); it has no code of its own.
