/* The public C API, used from C (this file is also compiled as C++ by
 * test_capi_cpp.cpp). Usage: test_capi PACKAGE. Exits non-zero on failure. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "blvd/blvd.h"

static int failures = 0;
#define EXPECT(cond)                                                  \
  do {                                                                \
    if (!(cond)) {                                                    \
      fprintf(stderr, "%s:%d: expected %s\n", __FILE__, __LINE__, #cond); \
      ++failures;                                                     \
    }                                                                 \
  } while (0)

int main(int argc, char** argv) {
  blvd_runtime_desc desc;
  blvd_runtime* rt = NULL;
  blvd_runtime_info info;
  blvd_frame_stats fs;
  unsigned char* px;
  size_t i, lit = 0, n;
  if (argc < 2) {
    fprintf(stderr, "usage: %s PACKAGE\n", argv[0]);
    return 2;
  }
  /* Version: header and library agree. */
  EXPECT(blvd_version_number() == BLVD_VERSION_NUMBER);
  EXPECT(strchr(blvd_version_string(), '.') != NULL);
  EXPECT(strcmp(blvd_status_string(BLVD_OK), "ok") == 0);
  EXPECT(strlen(blvd_status_string(BLVD_ERR_CORRUPT)) > 0);
  EXPECT(strcmp(blvd_status_string((blvd_status)12345), "unknown status") == 0);

  /* Misuse and bad arguments never crash. */
  EXPECT(blvd_runtime_create(NULL, &rt) == BLVD_ERR_MISUSE);
  EXPECT(rt == NULL);
  EXPECT(blvd_render(NULL, NULL) == BLVD_ERR_MISUSE);
  EXPECT(blvd_set_pose_local(NULL, 0, 0, 0, 0) == BLVD_ERR_MISUSE);
  blvd_runtime_destroy(NULL);
  memset(&desc, 0, sizeof desc);
  EXPECT(blvd_runtime_create(&desc, &rt) == BLVD_ERR_INVALID_ARG); /* no package */
  EXPECT(strstr(blvd_last_error(NULL), "package_path") != NULL);
  desc.package_path = "/nonexistent/city.blvd";
  EXPECT(blvd_runtime_create(&desc, &rt) == BLVD_ERR_IO);
  EXPECT(strstr(blvd_last_error(NULL), "/nonexistent/city.blvd") != NULL);
  desc.package_path = argv[0]; /* an ELF file: foreign */
  EXPECT(blvd_runtime_create(&desc, &rt) == BLVD_ERR_CORRUPT);
  EXPECT(rt == NULL);

  /* Defaults fill zero fields. */
  {
    blvd_runtime_desc d;
    memset(&d, 0, sizeof d);
    d = blvd_runtime_desc_defaults(&d);
    EXPECT(d.width == 800 && d.height == 480 && d.fov_y_deg == 45.0f && d.struct_size == sizeof d);
  }

  /* A real runtime on the baked package (small frame to keep it quick). */
  memset(&desc, 0, sizeof desc);
  desc.struct_size = sizeof desc;
  desc.package_path = argv[1];
  desc.width = 320;
  desc.height = 192;
  if (blvd_runtime_create(&desc, &rt) != BLVD_OK) {
    fprintf(stderr, "create failed: %s\n", blvd_last_error(NULL));
    return 1;
  }
  memset(&info, 0, sizeof info);
  info.struct_size = sizeof info;
  EXPECT(blvd_runtime_get_info(rt, &info) == BLVD_OK);
  EXPECT(info.block_count > 0 && info.cell_count > 0 && info.triangle_count > 0);
  EXPECT(info.backend != NULL && info.gl_renderer != NULL);
  EXPECT(fabs(info.origin_lat - 43.73) < 0.1 && fabs(info.origin_lon - 7.42) < 0.1); /* Monaco */

  EXPECT(blvd_read_pixels(rt, NULL, 0) == BLVD_ERR_MISUSE);
  EXPECT(blvd_set_pose_geo(rt, 123.0, 7.42, 0, 0) == BLVD_ERR_INVALID_ARG);
  EXPECT(strstr(blvd_last_error(rt), "latitude") != NULL);
  EXPECT(blvd_set_pose_local(rt, NAN, 0, 0, 0) == BLVD_ERR_INVALID_ARG);
  EXPECT(blvd_set_pose_local(rt, 0, 0, 0, 95.0f) == BLVD_ERR_INVALID_ARG);
  EXPECT(blvd_set_pose_geo(rt, info.origin_lat, info.origin_lon, 90.0f, 0.0f) == BLVD_OK);
  memset(&fs, 0, sizeof fs);
  fs.struct_size = sizeof fs;
  EXPECT(blvd_render(rt, &fs) == BLVD_OK);
  EXPECT(fs.frame_ms > 0 && fs.draw_calls > 0);
  n = (size_t)320 * 192 * 4;
  px = (unsigned char*)malloc(n);
  EXPECT(blvd_read_pixels(rt, px, n - 1) == BLVD_ERR_INVALID_ARG);
  EXPECT(blvd_read_pixels(rt, px, n) == BLVD_OK);
  for (i = 0; i < n; i += 4) lit += (px[i] | px[i + 1] | px[i + 2]) != 0;
  EXPECT(lit == n / 4); /* sky, ground or city everywhere: nothing left black */
  free(px);
  blvd_runtime_destroy(rt);
  if (failures) fprintf(stderr, "%d failures\n", failures);
  else printf("C API: all checks passed\n");
  return failures ? 1 : 0;
}
