/* The public C API, used from C (this file is also compiled as C++ by
 * test_capi_cpp.cpp). Usage: test_capi PACKAGE. Exits non-zero on failure. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <stddef.h>
#include <string.h>

#include "blvd/blvd.h"
#include "expect.h"


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
  EXPECT(blvd_runtime_create(NULL, &rt) == BLVD_ERR_INVALID_ARG);
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

  /* Enum fields and arguments holding ints outside their enums are refused
   * (C lets a host store any int there). */
  memset(&desc, 0, sizeof desc);
  desc.struct_size = sizeof desc;
  desc.package_path = argv[1];
  desc.mode = (blvd_render_mode)99;
  EXPECT(blvd_runtime_create(&desc, &rt) == BLVD_ERR_INVALID_ARG);
  EXPECT(strstr(blvd_last_error(NULL), "render mode") != NULL);
  desc.mode = BLVD_MODE_BLVD;
  desc.backend = (blvd_backend)-3;
  EXPECT(blvd_runtime_create(&desc, &rt) == BLVD_ERR_INVALID_ARG);
  desc.backend = BLVD_BACKEND_AUTO;
  desc.prefetch_priority = 3; /* past BLVD_PREFETCH_IDLE_ANYTIME */
  EXPECT(blvd_runtime_create(&desc, &rt) == BLVD_ERR_INVALID_ARG);
  EXPECT(rt == NULL);

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

  EXPECT(blvd_read_pixels(rt, NULL, 0) == BLVD_ERR_INVALID_ARG);
  EXPECT(blvd_set_pose_geo(rt, 123.0, 7.42, 0, 0) == BLVD_ERR_INVALID_ARG);
  EXPECT(strstr(blvd_last_error(rt), "latitude") != NULL);
  EXPECT(blvd_set_pose_local(rt, NAN, 0, 0, 0) == BLVD_ERR_INVALID_ARG);
  EXPECT(blvd_set_pose_local(rt, 0, 0, 0, 95.0f) == BLVD_ERR_INVALID_ARG);
  EXPECT(blvd_set_render_mode(rt, (blvd_render_mode)42, 0) == BLVD_ERR_INVALID_ARG);
  EXPECT(strstr(blvd_last_error(rt), "render mode") != NULL);
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
  {
    /* Object ids: block + 1, BLVD_ITEM_IMPOSTOR | layer, 0 for sky and ground
     * (of the full model: the cell of the frame above may still be loading). */
    uint32_t* ids = (uint32_t*)malloc(320 * 192 * sizeof(uint32_t));
    size_t blocks = 0, sky = 0;
    EXPECT(blvd_set_render_mode(rt, BLVD_MODE_FULL, 0) == BLVD_OK);
    EXPECT(blvd_render(rt, &fs) == BLVD_OK);
    EXPECT(blvd_read_items(rt, ids, 320 * 192 - 1) == BLVD_ERR_INVALID_ARG);
    EXPECT(blvd_read_items(rt, ids, 320 * 192) == BLVD_OK);
    for (i = 0; i < 320 * 192; ++i) {
      sky += ids[i] == 0;
      blocks += ids[i] != 0 && !(ids[i] & BLVD_ITEM_IMPOSTOR) && ids[i] <= info.block_count;
    }
    EXPECT(sky > 0 && blocks > 0);
    EXPECT(blvd_read_pixels(rt, px, n) == BLVD_ERR_MISUSE); /* the ids replaced the frame */
    EXPECT(blvd_render(rt, &fs) == BLVD_OK);
    EXPECT(blvd_read_pixels(rt, px, n) == BLVD_OK);
    EXPECT(blvd_set_render_mode(rt, BLVD_MODE_BLVD, 0) == BLVD_OK);
    free(ids);
  }
  free(px);

  /* Tracking: fixes along a street at 10 m/s; the pose becomes valid, stays
   * near the fixes, and the render follows it. */
  {
    blvd_gnss_fix fix;
    blvd_odometry odo;
    blvd_pose pose;
    blvd_odometry_calibration cal;
    int k;
    const double lat0 = 43.735370, lon0 = 7.417288, hdg = 211.0 * 3.14159265358979 / 180.0;
    EXPECT(blvd_feed_gnss(rt, NULL) == BLVD_ERR_INVALID_ARG);
    EXPECT(blvd_feed_gnss(NULL, NULL) == BLVD_ERR_MISUSE);
    /* The odometry calibration a host stores between drives: the defaults, a stored one
     * (sigmas raised to their floors), an impossible one refused with its values named. */
    memset(&cal, 0, sizeof cal);
    cal.struct_size = sizeof cal;
    EXPECT(blvd_get_odometry_calibration(rt, &cal) == BLVD_OK);
    EXPECT(cal.speed_scale == 1.0 && fabs(cal.speed_scale_sigma - 0.05) < 1e-9 && cal.yaw_rate_bias_dps == 0.0);
    cal.speed_scale = 1.03;
    cal.speed_scale_sigma = 0.0;
    cal.yaw_rate_bias_dps = 0.2;
    cal.yaw_rate_bias_sigma_dps = 0.01;
    EXPECT(blvd_set_odometry_calibration(rt, &cal) == BLVD_OK);
    memset(&cal, 0, sizeof cal);
    cal.struct_size = sizeof cal;
    EXPECT(blvd_get_odometry_calibration(rt, &cal) == BLVD_OK);
    EXPECT(cal.speed_scale == 1.03 && fabs(cal.speed_scale_sigma - 0.002) < 1e-12);
    EXPECT(fabs(cal.yaw_rate_bias_dps - 0.2) < 1e-12 && fabs(cal.yaw_rate_bias_sigma_dps - 0.05) < 1e-12);
    cal.speed_scale = 3.0;
    EXPECT(blvd_set_odometry_calibration(rt, &cal) == BLVD_ERR_INVALID_ARG);
    EXPECT(strstr(blvd_last_error(rt), "speed_scale 3 ") != NULL);
    cal.speed_scale = 1.0;
    cal.struct_size = 8;
    EXPECT(blvd_set_odometry_calibration(rt, &cal) == BLVD_ERR_INVALID_ARG);
    EXPECT(blvd_set_odometry_calibration(rt, NULL) == BLVD_ERR_INVALID_ARG);
    EXPECT(blvd_get_odometry_calibration(NULL, &cal) == BLVD_ERR_MISUSE);
    memset(&cal, 0, sizeof cal);
    cal.struct_size = sizeof cal;
    EXPECT(blvd_get_odometry_calibration(rt, &cal) == BLVD_OK);
    EXPECT(cal.speed_scale == 1.03); /* the refused ones changed nothing */
    cal.speed_scale = 0.9; /* the wheels read 10 % slow, +- 5 %: wrong for the feed below */
    cal.speed_scale_sigma = 0.05;
    cal.yaw_rate_bias_dps = 0.0;
    EXPECT(blvd_set_odometry_calibration(rt, &cal) == BLVD_OK);
    for (k = 0; k < 10; ++k) {
      const double d = 10.0 * k; /* metres travelled */
      memset(&fix, 0, sizeof fix);
      fix.struct_size = sizeof fix;
      fix.t = 100.0 + k;
      fix.lat = lat0 + d * cos(hdg) / 111132.0;
      fix.lon = lon0 + d * sin(hdg) / (111320.0 * cos(lat0 * 3.14159265358979 / 180.0));
      fix.speed_mps = 10.0f;
      fix.track_deg = 211.0f;
      fix.hdop = 1.0f;
      fix.mode = BLVD_GNSS_MODE_3D;
      fix.flags = BLVD_GNSS_HAS_TIME | BLVD_GNSS_HAS_LATLON | BLVD_GNSS_HAS_SPEED | BLVD_GNSS_HAS_TRACK |
                  BLVD_GNSS_HAS_HDOP;
      EXPECT(blvd_feed_gnss(rt, &fix) == BLVD_OK);
      memset(&odo, 0, sizeof odo);
      odo.struct_size = sizeof odo;
      odo.t = 100.0 + k + 0.5;
      odo.speed_mps = 10.0;
      odo.flags = BLVD_ODO_SPEED | BLVD_ODO_YAW_RATE;
      EXPECT(blvd_feed_odometry(rt, &odo) == BLVD_OK);
    }
    memset(&pose, 0, sizeof pose);
    pose.struct_size = sizeof pose;
    EXPECT(blvd_get_pose(rt, 109.0, &pose) == BLVD_OK);
    EXPECT(pose.flags & BLVD_POSE_VALID);
    EXPECT(fabs(pose.lat - fix.lat) < 30.0 / 111132.0 && fabs(pose.lon - fix.lon) < 30.0 / 80000.0);
    EXPECT(fabs(pose.speed_mps - 10.0) < 2.0);
    /* The fixes say 10 m/s, the odometry 10 m/s: the scale moves from 0.9 towards 1. */
    memset(&cal, 0, sizeof cal);
    cal.struct_size = sizeof cal;
    EXPECT(blvd_get_odometry_calibration(rt, &cal) == BLVD_OK);
    EXPECT(cal.speed_scale > 0.97 && cal.speed_scale < 1.03);
    EXPECT(cal.speed_scale_sigma < 0.05);
    EXPECT(blvd_get_pose(rt, NAN, &pose) == BLVD_ERR_INVALID_ARG);
    memset(&fs, 0, sizeof fs);
    fs.struct_size = sizeof fs;
    EXPECT(blvd_set_camera_source(rt, BLVD_CAMERA_TRACKED) == BLVD_OK);
    EXPECT(blvd_render(rt, &fs) == BLVD_OK); /* the camera follows the tracked pose */
    EXPECT(fs.cell != BLVD_NO_CELL);

    /* Key-off: the pose to keep, with its sigmas; key-on: the next drive starts from it
     * and has a matched pose, dead reckoning, before any fix. */
    {
      blvd_start_pose sp;
      blvd_pose again;
      unsigned char raw[sizeof(blvd_pose)];
      blvd_pose* old = (blvd_pose*)raw;
      EXPECT(blvd_get_pose(rt, 109.0, &pose) == BLVD_OK);
      EXPECT(pose.pos_sigma_m > 0.0 && pose.pos_sigma_m < 10.0);
      EXPECT(pose.heading_sigma_deg > 0.0 && pose.heading_sigma_deg < 10.0);
      /* A host built against the struct before those two fields gets nothing written past it. */
      memset(raw, 0xab, sizeof raw);
      old->struct_size = (uint32_t)offsetof(blvd_pose, pos_sigma_m);
      EXPECT(blvd_get_pose(rt, 109.0, old) == BLVD_OK);
      EXPECT(old->lat == pose.lat && raw[offsetof(blvd_pose, pos_sigma_m)] == 0xab && raw[sizeof raw - 1] == 0xab);

      memset(&sp, 0, sizeof sp);
      sp.struct_size = sizeof sp;
      sp.t = 500.0;
      sp.lat = pose.lat;
      sp.lon = pose.lon;
      sp.heading_deg = pose.heading_deg;
      sp.sigma_m = pose.pos_sigma_m;
      sp.heading_sigma_deg = pose.heading_sigma_deg;
      EXPECT(blvd_set_start_pose(rt, &sp) == BLVD_OK);
      memset(&again, 0, sizeof again);
      again.struct_size = sizeof again;
      EXPECT(blvd_get_pose(rt, 500.0, &again) == BLVD_OK);
      EXPECT((again.flags & (BLVD_POSE_VALID | BLVD_POSE_HEADING_VALID | BLVD_POSE_DEAD_RECKONING)) ==
             (BLVD_POSE_VALID | BLVD_POSE_HEADING_VALID | BLVD_POSE_DEAD_RECKONING));
      EXPECT(fabs(again.lat - pose.lat) < 1e-7 && fabs(again.lon - pose.lon) < 1e-7);
      EXPECT(fabs(again.heading_deg - pose.heading_deg) < 1e-6);
      EXPECT(fabs(again.pos_sigma_m - (pose.pos_sigma_m > 0.5 ? pose.pos_sigma_m : 0.5)) < 1e-6);
      if (pose.flags & BLVD_POSE_MATCHED) EXPECT((again.flags & BLVD_POSE_MATCHED) && again.cell == pose.cell);
      memset(&fs, 0, sizeof fs);
      fs.struct_size = sizeof fs;
      EXPECT(blvd_render(rt, &fs) == BLVD_OK); /* the camera is at the start pose */
      EXPECT(fs.cell != 0xffffffffu);

      sp.lat = 95.0; /* refused, naming the value; nothing changes */
      EXPECT(blvd_set_start_pose(rt, &sp) == BLVD_ERR_INVALID_ARG);
      EXPECT(strstr(blvd_last_error(rt), "lat 95") != NULL);
      sp.lat = pose.lat;
      sp.sigma_m = -1.0;
      EXPECT(blvd_set_start_pose(rt, &sp) == BLVD_ERR_INVALID_ARG);
      sp.sigma_m = 1.0;
      sp.struct_size = (uint32_t)offsetof(blvd_start_pose, heading_sigma_deg);
      EXPECT(blvd_set_start_pose(rt, &sp) == BLVD_ERR_INVALID_ARG);
      EXPECT(strstr(blvd_last_error(rt), "struct_size") != NULL);
      EXPECT(blvd_set_start_pose(rt, NULL) == BLVD_ERR_INVALID_ARG);
      EXPECT(blvd_set_start_pose(NULL, &sp) == BLVD_ERR_MISUSE);
      EXPECT(blvd_get_pose(rt, 500.0, &again) == BLVD_OK);
      EXPECT(fabs(again.lat - pose.lat) < 1e-7 && fabs(again.lon - pose.lon) < 1e-7);
    }
  }
  blvd_runtime_destroy(rt);
  if (failures) fprintf(stderr, "%d failures\n", failures);
  else printf("C API: all checks passed\n");
  return failures ? 1 : 0;
}
