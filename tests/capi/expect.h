/* EXPECT(cond) for the C tests of the C API: prints the failed condition
 * with its line and counts it in `failures` (main returns non-zero then). */
#ifndef BLVD_TESTS_CAPI_EXPECT_H
#define BLVD_TESTS_CAPI_EXPECT_H
#include <stdio.h>

static int failures = 0;
#define EXPECT(cond)                                                      \
  do {                                                                    \
    if (!(cond)) {                                                        \
      fprintf(stderr, "%s:%d: expected %s\n", __FILE__, __LINE__, #cond); \
      ++failures;                                                         \
    }                                                                     \
  } while (0)

#endif
