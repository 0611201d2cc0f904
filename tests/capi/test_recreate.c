/* A host that destroys its runtime and creates it again (after a GPU reset,
 * for a new package, on a display change) keeps nothing of the runs before:
 * resident memory after the 50th create, frame and destroy is within 2 MiB of
 * what it was after the 20th. CTest runs it with MALLOC_ARENA_MAX=2: glibc
 * otherwise gives the loader threads of each new runtime new malloc arenas,
 * up to eight a core, each keeping what it touched (a step of 5 MiB at a
 * cycle that varies, then flat): bounded, and glibc's, not a leak.
 * Usage: test_recreate_c PACKAGE. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "blvd/blvd.h"

static long residentKib(void) {
  char line[256];
  long kib = -1;
  FILE* f = fopen("/proc/self/status", "r");
  if (!f) return -1;
  while (fgets(line, sizeof line, f))
    if (strncmp(line, "VmRSS:", 6) == 0) kib = atol(line + 6);
  fclose(f);
  return kib;
}

static int cycle(const char* package) {
  blvd_runtime_desc d;
  blvd_runtime* rt = NULL;
  memset(&d, 0, sizeof d);
  d.package_path = package;
  d.width = 160;
  d.height = 96;
  if (blvd_runtime_create(&d, &rt) != BLVD_OK) {
    fprintf(stderr, "create: %s\n", blvd_last_error(NULL));
    return 0;
  }
  int ok = blvd_set_pose_geo(rt, 43.735370, 7.417288, 211.0f, 0.0f) == BLVD_OK &&
           blvd_wait_resident(rt, 60000) == BLVD_OK && blvd_render(rt, NULL) == BLVD_OK;
  if (!ok) fprintf(stderr, "drive: %s\n", blvd_last_error(rt));
  blvd_runtime_destroy(rt);
  return ok;
}

int main(int argc, char** argv) {
  long settled = 0, now = 0;
  int i;
  if (argc < 2) {
    fprintf(stderr, "usage: %s PACKAGE\n", argv[0]);
    return 2;
  }
  for (i = 1; i <= 50; ++i) {
    if (!cycle(argv[1])) return 1;
    now = residentKib();
    if (i == 20) settled = now;
  }
  printf("resident after the 20th cycle %ld KiB, after the 50th %ld KiB\n", settled, now);
  if (settled <= 0 || now - settled > 2048) {
    fprintf(stderr, "resident memory grew by %ld KiB over 30 cycles\n", now - settled);
    return 1;
  }
  return 0;
}
