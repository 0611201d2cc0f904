// The same C API checks, compiled as C++ (the header must be valid in both).
#include "test_capi.c"
