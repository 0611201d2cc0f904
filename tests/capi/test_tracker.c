/* The tracker without a renderer (blvd_tracker_*), from C: created from a
 * package's graph or from an origin alone, fed the same fixes and odometry as
 * a runtime, and giving the same poses as blvd_get_pose. Usage: test_tracker
 * PACKAGE. Exits non-zero on failure. */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "blvd/blvd.h"
#include "expect.h"


static const double kLat0 = 43.735370, kLon0 = 7.417288, kHdgDeg = 211.0;

/* Second k of a drive along heading kHdgDeg at 10 m/s from (kLat0, kLon0), `off_m` further on:
 * its fix at 100 + k and its odometry half a second later. */
static void driveFix(int k, double off_m, blvd_gnss_fix* fix) {
  const double hdg = kHdgDeg * 3.14159265358979 / 180.0;
  const double d = 10.0 * k + off_m;
  memset(fix, 0, sizeof *fix);
  fix->struct_size = sizeof *fix;
  fix->t = 100.0 + k;
  fix->lat = kLat0 + d * cos(hdg) / 111132.0;
  fix->lon = kLon0 + d * sin(hdg) / (111320.0 * cos(kLat0 * 3.14159265358979 / 180.0));
  fix->speed_mps = 10.0f;
  fix->track_deg = (float)kHdgDeg;
  fix->hdop = 1.0f;
  fix->mode = BLVD_GNSS_MODE_3D;
  fix->flags = BLVD_GNSS_HAS_TIME | BLVD_GNSS_HAS_LATLON | BLVD_GNSS_HAS_SPEED | BLVD_GNSS_HAS_TRACK |
               BLVD_GNSS_HAS_HDOP;
}

static void driveOdometry(int k, blvd_odometry* odo) {
  memset(odo, 0, sizeof *odo);
  odo->struct_size = sizeof *odo;
  odo->t = 100.0 + k + 0.5;
  odo->speed_mps = 10.0;
  odo->flags = BLVD_ODO_SPEED | BLVD_ODO_YAW_RATE;
}

/* Ten seconds of that drive: a fix a second, odometry between. */
static void feedDrive(blvd_tracker* tr, blvd_runtime* rt) {
  int k;
  for (k = 0; k < 10; ++k) {
    blvd_gnss_fix fix;
    blvd_odometry odo;
    driveFix(k, 0.0, &fix);
    driveOdometry(k, &odo);
    if (tr) {
      EXPECT(blvd_tracker_feed_gnss(tr, &fix) == BLVD_OK);
      EXPECT(blvd_tracker_feed_odometry(tr, &odo) == BLVD_OK);
    }
    if (rt) {
      EXPECT(blvd_feed_gnss(rt, &fix) == BLVD_OK);
      EXPECT(blvd_feed_odometry(rt, &odo) == BLVD_OK);
    }
  }
}

static void checkCreateErrors(const char* self) {
  blvd_tracker_desc d;
  blvd_tracker* tr = NULL;
  EXPECT(blvd_tracker_create(NULL, &tr) == BLVD_ERR_INVALID_ARG && tr == NULL);
  memset(&d, 0, sizeof d);
  d.struct_size = sizeof d;
  EXPECT(blvd_tracker_create(&d, NULL) == BLVD_ERR_INVALID_ARG);
  d.package_path = "/nonexistent/city.blvd";
  EXPECT(blvd_tracker_create(&d, &tr) == BLVD_ERR_IO && tr == NULL);
  EXPECT(strstr(blvd_tracker_last_error(NULL), "/nonexistent/city.blvd") != NULL);
  d.package_path = self; /* an ELF file */
  EXPECT(blvd_tracker_create(&d, &tr) == BLVD_ERR_CORRUPT && tr == NULL);
  d.package_path = NULL;
  d.origin_lat = 95.0;
  EXPECT(blvd_tracker_create(&d, &tr) == BLVD_ERR_INVALID_ARG && tr == NULL);
  EXPECT(strstr(blvd_tracker_last_error(NULL), "origin_lat") != NULL);
  d.origin_lat = kLat0;
  d.eye_height_m = -1.0f;
  EXPECT(blvd_tracker_create(&d, &tr) == BLVD_ERR_INVALID_ARG && tr == NULL);
  blvd_tracker_destroy(NULL);
}

static void checkNullHandles(void) {
  blvd_pose pose;
  blvd_gnss_fix fix;
  memset(&fix, 0, sizeof fix);
  memset(&pose, 0, sizeof pose);
  EXPECT(blvd_tracker_feed_gnss(NULL, &fix) == BLVD_ERR_MISUSE);
  EXPECT(blvd_tracker_feed_odometry(NULL, NULL) == BLVD_ERR_MISUSE);
  EXPECT(blvd_tracker_feed_can_frame(NULL, NULL, NULL) == BLVD_ERR_MISUSE);
  EXPECT(blvd_tracker_get_pose(NULL, 0.0, &pose) == BLVD_ERR_MISUSE);
  EXPECT(blvd_tracker_get_odometry_calibration(NULL, NULL) == BLVD_ERR_MISUSE);
  EXPECT(blvd_tracker_set_odometry_calibration(NULL, NULL) == BLVD_ERR_MISUSE);
  EXPECT(blvd_tracker_set_start_pose(NULL, NULL) == BLVD_ERR_MISUSE);
  EXPECT(blvd_tracker_get_stats(NULL, NULL) == BLVD_ERR_MISUSE);
  EXPECT(blvd_get_tracking_stats(NULL, NULL) == BLVD_ERR_MISUSE);
}

/* A tracker on the package and a runtime on it, fed the same: the same pose. */
static void checkSameAsRuntime(const char* package) {
  blvd_tracker_desc d;
  blvd_tracker* tr = NULL;
  blvd_runtime_desc rd;
  blvd_runtime* rt = NULL;
  blvd_pose a, b;
  memset(&d, 0, sizeof d);
  d.struct_size = sizeof d;
  d.package_path = package;
  EXPECT(blvd_tracker_create(&d, &tr) == BLVD_OK && tr != NULL);
  memset(&rd, 0, sizeof rd);
  rd.struct_size = sizeof rd;
  rd.package_path = package;
  rd.width = 160;
  rd.height = 96;
  EXPECT(blvd_runtime_create(&rd, &rt) == BLVD_OK);
  if (!tr || !rt) {
    fprintf(stderr, "create: %s\n", blvd_last_error(NULL));
    blvd_tracker_destroy(tr);
    blvd_runtime_destroy(rt);
    ++failures;
    return;
  }
  EXPECT(blvd_tracker_feed_gnss(tr, NULL) == BLVD_ERR_INVALID_ARG);
  EXPECT(blvd_tracker_get_pose(tr, 0.0, NULL) == BLVD_ERR_INVALID_ARG);
  feedDrive(tr, rt);
  memset(&a, 0, sizeof a);
  a.struct_size = sizeof a;
  b = a;
  EXPECT(blvd_tracker_get_pose(tr, 109.0, &a) == BLVD_OK);
  EXPECT(blvd_get_pose(rt, 109.0, &b) == BLVD_OK);
  EXPECT(a.flags & BLVD_POSE_VALID);
  EXPECT(a.lat == b.lat && a.lon == b.lon && a.x == b.x && a.y == b.y);
  EXPECT(a.heading_deg == b.heading_deg && a.cell == b.cell && a.arc_m == b.arc_m && a.flags == b.flags);
  EXPECT(a.camera_x == b.camera_x && a.camera_z == b.camera_z);
  EXPECT(blvd_tracker_get_pose(tr, NAN, &a) == BLVD_ERR_INVALID_ARG);
  EXPECT(strstr(blvd_tracker_last_error(tr), "not finite") != NULL);
  {
    blvd_tracking_stats sa, sb;
    memset(&sa, 0, sizeof sa);
    sa.struct_size = sizeof sa;
    sb = sa;
    EXPECT(blvd_tracker_get_stats(tr, &sa) == BLVD_OK);
    EXPECT(blvd_get_tracking_stats(rt, &sb) == BLVD_OK);
    EXPECT(sa.gnss_fed == 10 && sa.odometry_fed == 10 && sa.gnss_used == 10);
    EXPECT(memcmp(&sa, &sb, sizeof sa) == 0);
    EXPECT(blvd_get_tracking_stats(rt, NULL) == BLVD_ERR_INVALID_ARG);
    EXPECT(strstr(blvd_last_error(rt), "stats is NULL") != NULL);
  }
  blvd_runtime_destroy(rt);
  blvd_tracker_destroy(tr);
}

/* Faults in the fed drive, counted while the pose goes on: every fix reported twice, one fix
 * 100 m ahead of the rest, one without a fix, a sample from before the filter's time; and a
 * struct_size that covers part of the struct gets that part. */
static void checkFaultsCounted(const char* package) {
  blvd_tracker_desc d;
  blvd_tracker* tr = NULL;
  blvd_tracking_stats st;
  blvd_pose p;
  int k;
  memset(&d, 0, sizeof d);
  d.struct_size = sizeof d;
  d.package_path = package;
  EXPECT(blvd_tracker_create(&d, &tr) == BLVD_OK && tr != NULL);
  if (!tr) return;
  for (k = 0; k < 12; ++k) {
    blvd_gnss_fix fix;
    blvd_odometry odo;
    driveFix(k, k == 8 ? 100.0 : 0.0, &fix);
    EXPECT(blvd_tracker_feed_gnss(tr, &fix) == BLVD_OK);
    EXPECT(blvd_tracker_feed_gnss(tr, &fix) == BLVD_OK);
    if (k == 5) {
      fix.t += 0.2;
      fix.mode = BLVD_GNSS_MODE_NO_FIX;
      EXPECT(blvd_tracker_feed_gnss(tr, &fix) == BLVD_OK);
    }
    driveOdometry(k, &odo);
    EXPECT(blvd_tracker_feed_odometry(tr, &odo) == BLVD_OK);
    memset(&p, 0, sizeof p);
    p.struct_size = sizeof p;
    EXPECT(blvd_tracker_get_pose(tr, 100.0 + k + 0.5, &p) == BLVD_OK);
    if (k == 8) EXPECT(p.flags & BLVD_POSE_VALID);
  }
  {
    blvd_odometry late;
    driveOdometry(3, &late); /* eight seconds old */
    EXPECT(blvd_tracker_feed_odometry(tr, &late) == BLVD_OK);
    EXPECT(blvd_tracker_get_pose(tr, 112.0, &p) == BLVD_OK && (p.flags & BLVD_POSE_VALID));
  }
  memset(&st, 0xAB, sizeof st);
  st.struct_size = sizeof st;
  EXPECT(blvd_tracker_get_stats(tr, &st) == BLVD_OK);
  EXPECT(st.gnss_fed == 25 && st.odometry_fed == 13 && st.late == 1);
  EXPECT(st.gnss_duplicates == 12);
  EXPECT(st.gnss_ignored == 1);
  EXPECT(st.gnss_rejected == 1 && st.gnss_used == 11);
  EXPECT(st.filter_resets == 0 && st.clock_steps == 0 && st.outages == 0 && st.queue_dropped == 0);
  EXPECT(st.longest_outage_s == 0.0);
  memset(&st, 0xAB, sizeof st);
  st.struct_size = (uint32_t)offsetof(blvd_tracking_stats, gnss_used);
  EXPECT(blvd_tracker_get_stats(tr, &st) == BLVD_OK);
  EXPECT(st.queue_dropped == 0 && st.gnss_used == 0xABABABABABABABABull);
  EXPECT(blvd_tracker_get_stats(tr, NULL) == BLVD_ERR_INVALID_ARG);
  blvd_tracker_destroy(tr);
}

/* No package: fusion and dead reckoning in the origin's frame, never matched;
 * the calibration and start pose as on a runtime. */
static void checkWithoutPackage(void) {
  blvd_tracker_desc d;
  blvd_tracker* tr = NULL;
  blvd_pose p;
  blvd_odometry_calibration cal;
  blvd_start_pose sp;
  memset(&d, 0, sizeof d);
  d.struct_size = sizeof d;
  d.origin_lat = kLat0;
  d.origin_lon = kLon0;
  EXPECT(blvd_tracker_create(&d, &tr) == BLVD_OK && tr != NULL);
  if (!tr) return;
  feedDrive(tr, NULL);
  memset(&p, 0, sizeof p);
  p.struct_size = sizeof p;
  EXPECT(blvd_tracker_get_pose(tr, 109.0, &p) == BLVD_OK);
  EXPECT((p.flags & BLVD_POSE_VALID) && !(p.flags & BLVD_POSE_MATCHED) && p.cell == 0xffffffffu);
  /* 90 m along 211 degrees from the origin: x = 90 sin(211), y = 90 cos(211), within the fixes' noise. */
  EXPECT(fabs(p.x - 90.0 * sin(kHdgDeg * 3.14159265358979 / 180.0)) < 15.0);
  EXPECT(fabs(p.y - 90.0 * cos(kHdgDeg * 3.14159265358979 / 180.0)) < 15.0);
  EXPECT(fabs(p.camera_z - 1.5) < 1e-9); /* the default eye height */

  memset(&cal, 0, sizeof cal);
  cal.struct_size = sizeof cal;
  EXPECT(blvd_tracker_get_odometry_calibration(tr, &cal) == BLVD_OK);
  EXPECT(cal.speed_scale > 0.9 && cal.speed_scale < 1.1);
  cal.speed_scale = 3.0;
  EXPECT(blvd_tracker_set_odometry_calibration(tr, &cal) == BLVD_ERR_INVALID_ARG);
  EXPECT(strstr(blvd_tracker_last_error(tr), "speed_scale 3 ") != NULL);
  EXPECT(blvd_tracker_set_odometry_calibration(tr, NULL) == BLVD_ERR_INVALID_ARG);

  memset(&sp, 0, sizeof sp);
  sp.struct_size = sizeof sp;
  sp.t = 500.0;
  sp.lat = kLat0;
  sp.lon = kLon0;
  sp.heading_deg = 90.0;
  sp.sigma_m = 1.0;
  sp.heading_sigma_deg = 2.0;
  EXPECT(blvd_tracker_set_start_pose(tr, &sp) == BLVD_OK);
  EXPECT(blvd_tracker_last_error(tr)[0] == '\0');
  EXPECT(blvd_tracker_get_pose(tr, 500.0, &p) == BLVD_OK);
  EXPECT(fabs(p.lat - kLat0) < 1e-7 && fabs(p.lon - kLon0) < 1e-7 && fabs(p.heading_deg - 90.0) < 1e-6);
  sp.lat = 95.0;
  EXPECT(blvd_tracker_set_start_pose(tr, &sp) == BLVD_ERR_INVALID_ARG);
  EXPECT(strstr(blvd_tracker_last_error(tr), "lat 95") != NULL);
  blvd_tracker_destroy(tr);
}

int main(int argc, char** argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: %s PACKAGE\n", argv[0]);
    return 2;
  }
  checkCreateErrors(argv[0]);
  checkNullHandles();
  checkSameAsRuntime(argv[1]);
  checkFaultsCounted(argv[1]);
  checkWithoutPackage();
  if (failures) fprintf(stderr, "%d failures\n", failures);
  else printf("tracker C API: all checks passed\n");
  return failures ? 1 : 0;
}
