/* Poses off the map, from C: a host pose 700 km from the package is refused
 * (BLVD_ERR_OFF_MAP) and the frames draw sky and ground, flagged, until a pose
 * on the map; fixes that leave the map give an off_map pose with no cell
 * (runtime and standalone tracker alike), never Monaco's nearest cell, and
 * tracking resumes when they come back. Usage: test_off_map PACKAGE. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "blvd/blvd.h"
#include "expect.h"

static const double kLat = 43.735370, kLon = 7.417288; /* a street in Monaco */
static const double kFarLat = 50.0, kFarLon = 7.4246;   /* 700 km north */

static blvd_frame_stats renderOnce(blvd_runtime* rt) {
  blvd_frame_stats fs;
  memset(&fs, 0, sizeof fs);
  fs.struct_size = sizeof fs;
  EXPECT(blvd_render(rt, &fs) == BLVD_OK);
  return fs;
}

/* The host's pose: refused off the map, drawn as sky and ground, back on the map drawn again. */
static void hostPose(blvd_runtime* rt) {
  blvd_frame_stats fs;
  EXPECT(blvd_set_pose_geo(rt, kLat, kLon, 211.0f, 0.0f) == BLVD_OK);
  EXPECT(blvd_wait_resident(rt, 60000) == BLVD_OK);
  fs = renderOnce(rt);
  EXPECT(fs.cell != BLVD_NO_CELL && !(fs.flags & BLVD_FRAME_OFF_MAP) && fs.blocks_drawn > 0);

  EXPECT(blvd_set_pose_geo(rt, kFarLat, kFarLon, 304.0f, 0.0f) == BLVD_ERR_OFF_MAP);
  EXPECT(strstr(blvd_last_error(rt), "off the map") != NULL);
  EXPECT(strstr(blvd_last_error(rt), "lat 50.000000, lon 7.424600") != NULL);
  EXPECT(strstr(blvd_last_error(rt), " km outside") != NULL);
  EXPECT(strcmp(blvd_status_string(BLVD_ERR_OFF_MAP), "unknown status") != 0);
  fs = renderOnce(rt);
  EXPECT(fs.cell == BLVD_NO_CELL && (fs.flags & BLVD_FRAME_OFF_MAP));
  EXPECT(fs.blocks_drawn == 0 && fs.impostor_layers == 0);
  /* In every mode: the full model too draws nothing there. */
  EXPECT(blvd_set_render_mode(rt, BLVD_MODE_FULL, 0.0f) == BLVD_OK);
  fs = renderOnce(rt);
  EXPECT((fs.flags & BLVD_FRAME_OFF_MAP) && fs.blocks_drawn == 0);
  EXPECT(blvd_set_render_mode(rt, BLVD_MODE_BLVD, 0.0f) == BLVD_OK);
  /* Local coordinates too; within the margin a pose is still on the map. */
  EXPECT(blvd_set_pose_local(rt, 1.0e6, 0.0, 0.0f, 0.0f) == BLVD_ERR_OFF_MAP);
  EXPECT(strstr(blvd_last_error(rt), "x 1000000.0 m, y 0.0 m") != NULL);

  EXPECT(blvd_set_pose_geo(rt, kLat, kLon, 211.0f, 0.0f) == BLVD_OK);
  fs = renderOnce(rt);
  EXPECT(fs.cell != BLVD_NO_CELL && !(fs.flags & BLVD_FRAME_OFF_MAP) && fs.blocks_drawn > 0);
}

static blvd_gnss_fix fixAt(double t, double lat, double lon) {
  blvd_gnss_fix fix;
  memset(&fix, 0, sizeof fix);
  fix.struct_size = sizeof fix;
  fix.t = t;
  fix.lat = lat;
  fix.lon = lon;
  fix.mode = BLVD_GNSS_MODE_3D;
  fix.hdop = 1.0f;
  fix.flags = BLVD_GNSS_HAS_TIME | BLVD_GNSS_HAS_LATLON | BLVD_GNSS_HAS_HDOP;
  return fix;
}

/* Fixes at one place from t0, one a second; the pose after the last. */
static blvd_pose feedRuntime(blvd_runtime* rt, double t0, int n, double lat, double lon) {
  blvd_pose pose;
  int k;
  for (k = 0; k < n; ++k) {
    const blvd_gnss_fix fix = fixAt(t0 + k, lat, lon);
    EXPECT(blvd_feed_gnss(rt, &fix) == BLVD_OK);
  }
  memset(&pose, 0, sizeof pose);
  pose.struct_size = sizeof pose;
  EXPECT(blvd_get_pose(rt, t0 + n - 1, &pose) == BLVD_OK);
  return pose;
}

/* The runtime's tracker drives the camera: off the map the pose says so and the
 * frame draws no cell; back on the map it matches again. */
static void trackedPose(blvd_runtime* rt) {
  blvd_pose pose;
  blvd_frame_stats fs;
  pose = feedRuntime(rt, 100.0, 5, kLat, kLon);
  EXPECT((pose.flags & BLVD_POSE_MATCHED) && !(pose.flags & BLVD_POSE_OFF_MAP) && pose.cell != BLVD_NO_CELL);
  EXPECT(blvd_set_camera_source(rt, BLVD_CAMERA_TRACKED) == BLVD_OK);
  fs = renderOnce(rt);
  EXPECT(fs.cell != BLVD_NO_CELL && !(fs.flags & BLVD_FRAME_OFF_MAP));
  /* Far fixes: the filter takes them after its outlier gate, then the pose is off the map. */
  pose = feedRuntime(rt, 105.0, 10, kFarLat, kFarLon);
  EXPECT((pose.flags & BLVD_POSE_VALID) && (pose.flags & BLVD_POSE_OFF_MAP));
  EXPECT(!(pose.flags & BLVD_POSE_MATCHED) && pose.cell == BLVD_NO_CELL);
  /* Where the fixes are, in the map's tangent plane (whose height is dropped: 4 km at 700 km). */
  EXPECT(fabs(pose.lat - kFarLat) < 0.1 && fabs(pose.lon - kFarLon) < 0.1);
  fs = renderOnce(rt);
  EXPECT(fs.cell == BLVD_NO_CELL && (fs.flags & BLVD_FRAME_OFF_MAP) && fs.blocks_drawn == 0);
  /* Back on the map. */
  pose = feedRuntime(rt, 115.0, 10, kLat, kLon);
  EXPECT((pose.flags & BLVD_POSE_MATCHED) && !(pose.flags & BLVD_POSE_OFF_MAP) && pose.cell != BLVD_NO_CELL);
  fs = renderOnce(rt);
  EXPECT(fs.cell != BLVD_NO_CELL && !(fs.flags & BLVD_FRAME_OFF_MAP));
  EXPECT(blvd_set_camera_source(rt, BLVD_CAMERA_HOST) == BLVD_OK);
}

/* The standalone tracker over the same package. */
static void standaloneTracker(const char* package) {
  blvd_tracker_desc td;
  blvd_tracker* tr = NULL;
  blvd_pose pose;
  int k;
  memset(&td, 0, sizeof td);
  td.struct_size = sizeof td;
  td.package_path = package;
  if (blvd_tracker_create(&td, &tr) != BLVD_OK) {
    fprintf(stderr, "tracker: %s\n", blvd_last_error(NULL));
    ++failures;
    return;
  }
  for (k = 0; k < 25; ++k) {
    const int leg = k / 5; /* on, off (10 fixes), back on (10 fixes) */
    const int off = leg >= 1 && leg < 3;
    const blvd_gnss_fix fix = fixAt(200.0 + k, off ? kFarLat : kLat, off ? kFarLon : kLon);
    EXPECT(blvd_tracker_feed_gnss(tr, &fix) == BLVD_OK);
    memset(&pose, 0, sizeof pose);
    pose.struct_size = sizeof pose;
    EXPECT(blvd_tracker_get_pose(tr, fix.t, &pose) == BLVD_OK);
    /* Never a cell while the fused position is far away. */
    if (fabs(pose.lat - kFarLat) < 1.0) EXPECT((pose.flags & BLVD_POSE_OFF_MAP) && pose.cell == BLVD_NO_CELL);
    if (k == 14) EXPECT(pose.flags & BLVD_POSE_OFF_MAP);
  }
  EXPECT((pose.flags & BLVD_POSE_MATCHED) && !(pose.flags & BLVD_POSE_OFF_MAP));
  blvd_tracker_destroy(tr);
}

int main(int argc, char** argv) {
  blvd_runtime_desc d;
  blvd_runtime* rt = NULL;
  if (argc < 2) {
    fprintf(stderr, "usage: %s PACKAGE\n", argv[0]);
    return 2;
  }
  memset(&d, 0, sizeof d);
  d.package_path = argv[1];
  d.width = 160;
  d.height = 96;
  if (blvd_runtime_create(&d, &rt) != BLVD_OK) {
    fprintf(stderr, "create: %s\n", blvd_last_error(NULL));
    return 1;
  }
  hostPose(rt);
  trackedPose(rt);
  blvd_runtime_destroy(rt);
  standaloneTracker(argv[1]);
  if (failures) fprintf(stderr, "%d failures\n", failures);
  else printf("off the map: all checks passed\n");
  return failures ? 1 : 0;
}
