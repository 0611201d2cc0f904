// stb's headers with our warning flags off (third-party code: keep -Wall and
// friends from drowning real findings). Define BLVD_STB_IMAGE and/or
// BLVD_STB_IMAGE_WRITE, and stb's IMPLEMENTATION macro where wanted, first.
#pragma once
#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wall"
#pragma GCC diagnostic ignored "-Wextra"
#pragma GCC diagnostic ignored "-Wpedantic"
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wunused-parameter"
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wimplicit-fallthrough"
#endif
#if defined(BLVD_STB_IMAGE)
#include <stb_image.h>
#endif
#if defined(BLVD_STB_IMAGE_WRITE)
#include <stb_image_write.h>
#endif
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif
