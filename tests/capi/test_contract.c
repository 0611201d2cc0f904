/* The API contract that blvd.h's Conventions state, checked rule by rule from
 * C: NULL handles and NULL arguments, struct_size on inputs and outputs, who
 * places the camera, and enum widths. Usage: test_contract PACKAGE. */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "blvd/blvd.h"
#include "expect.h"

static const double kLat = 43.735370, kLon = 7.417288;

static void nullHandles(void) {
  blvd_runtime_info info;
  blvd_stats st;
  blvd_pose pose;
  blvd_gnss_fix fix;
  blvd_odometry odo;
  blvd_odometry_calibration cal;
  blvd_start_pose sp;
  blvd_view view;
  blvd_can_frame frame;
  unsigned char px[4];
  uint32_t ids[1], cells[1] = {0};
  memset(&info, 0, sizeof info);
  memset(&st, 0, sizeof st);
  memset(&pose, 0, sizeof pose);
  memset(&fix, 0, sizeof fix);
  memset(&odo, 0, sizeof odo);
  memset(&cal, 0, sizeof cal);
  memset(&sp, 0, sizeof sp);
  memset(&view, 0, sizeof view);
  memset(&frame, 0, sizeof frame);
  EXPECT(blvd_runtime_get_info(NULL, &info) == BLVD_ERR_MISUSE);
  EXPECT(blvd_set_camera_source(NULL, BLVD_CAMERA_HOST) == BLVD_ERR_MISUSE);
  EXPECT(blvd_set_pose_geo(NULL, kLat, kLon, 0, 0) == BLVD_ERR_MISUSE);
  EXPECT(blvd_set_pose_local(NULL, 0, 0, 0, 0) == BLVD_ERR_MISUSE);
  EXPECT(blvd_set_render_mode(NULL, BLVD_MODE_FULL, 0) == BLVD_ERR_MISUSE);
  EXPECT(blvd_runtime_stats(NULL, &st) == BLVD_ERR_MISUSE);
  EXPECT(blvd_wait_resident(NULL, 1) == BLVD_ERR_MISUSE);
  EXPECT(blvd_set_route(NULL, cells, 1) == BLVD_ERR_MISUSE);
  EXPECT(blvd_render(NULL, NULL) == BLVD_ERR_MISUSE);
  EXPECT(blvd_render_views(NULL, &view, 1, NULL) == BLVD_ERR_MISUSE);
  EXPECT(blvd_read_pixels(NULL, px, sizeof px) == BLVD_ERR_MISUSE);
  EXPECT(blvd_read_items(NULL, ids, 1) == BLVD_ERR_MISUSE);
  EXPECT(blvd_feed_gnss(NULL, &fix) == BLVD_ERR_MISUSE);
  EXPECT(blvd_feed_odometry(NULL, &odo) == BLVD_ERR_MISUSE);
  EXPECT(blvd_get_pose(NULL, 0, &pose) == BLVD_ERR_MISUSE);
  EXPECT(blvd_get_odometry_calibration(NULL, &cal) == BLVD_ERR_MISUSE);
  EXPECT(blvd_set_odometry_calibration(NULL, &cal) == BLVD_ERR_MISUSE);
  EXPECT(blvd_set_start_pose(NULL, &sp) == BLVD_ERR_MISUSE);
  EXPECT(blvd_feed_can_frame(NULL, NULL, &frame) == BLVD_ERR_MISUSE);
  EXPECT(blvd_can_profile_decode(NULL, &frame, &odo) == BLVD_ERR_MISUSE);
  uint32_t n_ids = 0;
  EXPECT(blvd_can_profile_message_ids(NULL, NULL, 0, &n_ids) == BLVD_ERR_MISUSE);
  EXPECT(blvd_tracker_feed_gnss(NULL, &fix) == BLVD_ERR_MISUSE);
  EXPECT(blvd_tracker_get_pose(NULL, 0, &pose) == BLVD_ERR_MISUSE);
  blvd_runtime_destroy(NULL);
  blvd_tracker_destroy(NULL);
  blvd_can_profile_destroy(NULL);
}

static void nullArguments(blvd_runtime* rt, const char* package) {
  blvd_runtime_desc d;
  blvd_runtime* none = NULL;
  blvd_tracker_desc td;
  blvd_tracker* tr = NULL;
  blvd_can_profile* prof = NULL;
  blvd_vehicle v;
  uint64_t cpu = 0;
  memset(&d, 0, sizeof d);
  d.package_path = package;
  memset(&td, 0, sizeof td);
  td.package_path = package;
  EXPECT(blvd_runtime_create(NULL, &none) == BLVD_ERR_INVALID_ARG);
  EXPECT(blvd_runtime_create(&d, NULL) == BLVD_ERR_INVALID_ARG);
  EXPECT(blvd_memory_required(NULL, package, &cpu, NULL) == BLVD_ERR_INVALID_ARG);
  EXPECT(blvd_memory_required(&d, NULL, NULL, NULL) == BLVD_ERR_INVALID_ARG);
  EXPECT(blvd_tracker_create(NULL, &tr) == BLVD_ERR_INVALID_ARG);
  EXPECT(blvd_tracker_create(&td, NULL) == BLVD_ERR_INVALID_ARG);
  EXPECT(blvd_can_profile_create(NULL, &prof) == BLVD_ERR_INVALID_ARG);
  EXPECT(blvd_vehicle_from_name(NULL, &v) == BLVD_ERR_INVALID_ARG);
  EXPECT(blvd_runtime_get_info(rt, NULL) == BLVD_ERR_INVALID_ARG);
  EXPECT(blvd_runtime_stats(rt, NULL) == BLVD_ERR_INVALID_ARG);
  EXPECT(blvd_set_route(rt, NULL, 3) == BLVD_ERR_INVALID_ARG);
  EXPECT(blvd_render_views(rt, NULL, 1, NULL) == BLVD_ERR_INVALID_ARG);
  EXPECT(blvd_read_pixels(rt, NULL, 16) == BLVD_ERR_INVALID_ARG);
  EXPECT(blvd_read_items(rt, NULL, 16) == BLVD_ERR_INVALID_ARG);
  EXPECT(blvd_feed_gnss(rt, NULL) == BLVD_ERR_INVALID_ARG);
  EXPECT(blvd_feed_odometry(rt, NULL) == BLVD_ERR_INVALID_ARG);
  EXPECT(blvd_get_pose(rt, 0, NULL) == BLVD_ERR_INVALID_ARG);
  EXPECT(blvd_get_odometry_calibration(rt, NULL) == BLVD_ERR_INVALID_ARG);
  EXPECT(blvd_set_odometry_calibration(rt, NULL) == BLVD_ERR_INVALID_ARG);
  EXPECT(blvd_set_start_pose(rt, NULL) == BLVD_ERR_INVALID_ARG);
}

/* Inputs: struct_size 0 means this header's size, for every input struct. */
static void zeroStructSizes(blvd_runtime* rt) {
  blvd_gnss_fix fix;
  blvd_odometry odo;
  blvd_odometry_calibration cal;
  blvd_start_pose sp;
  blvd_view view;
  memset(&fix, 0, sizeof fix);
  fix.t = 1.0;
  fix.lat = kLat;
  fix.lon = kLon;
  fix.mode = BLVD_GNSS_MODE_3D;
  fix.flags = BLVD_GNSS_HAS_TIME | BLVD_GNSS_HAS_LATLON;
  EXPECT(blvd_feed_gnss(rt, &fix) == BLVD_OK);
  memset(&odo, 0, sizeof odo);
  odo.t = 1.5;
  odo.flags = BLVD_ODO_SPEED;
  EXPECT(blvd_feed_odometry(rt, &odo) == BLVD_OK);
  memset(&cal, 0, sizeof cal);
  cal.speed_scale = 1.0;
  EXPECT(blvd_set_odometry_calibration(rt, &cal) == BLVD_OK);
  memset(&sp, 0, sizeof sp);
  sp.t = 2.0;
  sp.lat = kLat;
  sp.lon = kLon;
  EXPECT(blvd_set_start_pose(rt, &sp) == BLVD_OK);
  memset(&view, 0, sizeof view);
  EXPECT(blvd_render_views(rt, &view, 1, NULL) == BLVD_OK);
}

/* Outputs: nothing is written past the caller's struct_size. */
static void outputsStopAtStructSize(blvd_runtime* rt) {
  unsigned char raw[1024];
  blvd_runtime_info* info = (blvd_runtime_info*)raw;
  blvd_stats* st = (blvd_stats*)raw;
  blvd_frame_stats* fs = (blvd_frame_stats*)raw;
  blvd_pose* pose = (blvd_pose*)raw;
  blvd_odometry_calibration* cal = (blvd_odometry_calibration*)raw;
  size_t cut;

  memset(raw, 0xab, sizeof raw);
  cut = offsetof(blvd_runtime_info, gl_renderer);
  info->struct_size = (uint32_t)cut;
  EXPECT(blvd_runtime_get_info(rt, info) == BLVD_OK);
  EXPECT(info->backend != NULL && raw[cut] == 0xab && raw[sizeof(blvd_runtime_info)] == 0xab);

  memset(raw, 0xab, sizeof raw);
  cut = offsetof(blvd_stats, gpu);
  st->struct_size = (uint32_t)cut;
  EXPECT(blvd_runtime_stats(rt, st) == BLVD_OK);
  EXPECT(st->max_resident_cells >= 2 && raw[cut] == 0xab);

  memset(raw, 0xab, sizeof raw);
  cut = offsetof(blvd_frame_stats, cell);
  fs->struct_size = (uint32_t)cut;
  EXPECT(blvd_render(rt, fs) == BLVD_OK);
  EXPECT(fs->triangles > 0 && raw[cut] == 0xab);

  memset(raw, 0xab, sizeof raw);
  cut = offsetof(blvd_pose, lat);
  pose->struct_size = (uint32_t)cut;
  EXPECT(blvd_get_pose(rt, 2.0, pose) == BLVD_OK);
  EXPECT(raw[cut] == 0xab);

  memset(raw, 0xab, sizeof raw);
  cut = offsetof(blvd_odometry_calibration, speed_scale_sigma);
  cal->struct_size = (uint32_t)cut;
  EXPECT(blvd_get_odometry_calibration(rt, cal) == BLVD_OK);
  EXPECT(cal->speed_scale > 0.5 && raw[cut] == 0xab);
}

/* The host places the camera until it hands it to the tracker, explicitly;
 * feeding alone never moves it. */
static void cameraSource(blvd_runtime* rt) {
  blvd_frame_stats fs;
  blvd_gnss_fix fix;
  blvd_pose pose;
  uint32_t host_cell;
  int k;
  memset(&fs, 0, sizeof fs);
  fs.struct_size = sizeof fs;
  EXPECT(blvd_set_camera_source(rt, (blvd_camera_source)7) == BLVD_ERR_INVALID_ARG);
  EXPECT(blvd_set_camera_source(rt, BLVD_CAMERA_HOST) == BLVD_OK);
  EXPECT(blvd_set_pose_geo(rt, kLat, kLon, 211.0f, 0.0f) == BLVD_OK);
  EXPECT(blvd_render(rt, &fs) == BLVD_OK);
  host_cell = fs.cell;
  EXPECT(host_cell != BLVD_NO_CELL);
  /* Fixes 400 m north: tracked, not followed. */
  for (k = 0; k < 5; ++k) {
    memset(&fix, 0, sizeof fix);
    fix.t = 100.0 + k;
    fix.lat = kLat + 400.0 / 111132.0;
    fix.lon = kLon;
    fix.mode = BLVD_GNSS_MODE_3D;
    fix.hdop = 1.0f;
    fix.flags = BLVD_GNSS_HAS_TIME | BLVD_GNSS_HAS_LATLON | BLVD_GNSS_HAS_HDOP;
    EXPECT(blvd_feed_gnss(rt, &fix) == BLVD_OK);
  }
  EXPECT(blvd_render(rt, &fs) == BLVD_OK);
  EXPECT(fs.cell == host_cell);
  memset(&pose, 0, sizeof pose);
  pose.struct_size = sizeof pose;
  EXPECT(blvd_get_pose(rt, 104.0, &pose) == BLVD_OK);
  EXPECT((pose.flags & BLVD_POSE_VALID) && fabs(pose.lat - (kLat + 400.0 / 111132.0)) < 30.0 / 111132.0);
  /* Handed to the tracker: the host may not place it, and frames follow the fixes. */
  EXPECT(blvd_set_camera_source(rt, BLVD_CAMERA_TRACKED) == BLVD_OK);
  EXPECT(blvd_set_pose_geo(rt, kLat, kLon, 0.0f, 0.0f) == BLVD_ERR_MISUSE);
  EXPECT(strstr(blvd_last_error(rt), "BLVD_CAMERA_HOST") != NULL);
  EXPECT(blvd_render(rt, &fs) == BLVD_OK);
  EXPECT(fs.cell != host_cell);
  /* And back. */
  EXPECT(blvd_set_camera_source(rt, BLVD_CAMERA_HOST) == BLVD_OK);
  EXPECT(blvd_set_pose_geo(rt, kLat, kLon, 211.0f, 0.0f) == BLVD_OK);
  EXPECT(blvd_render(rt, &fs) == BLVD_OK);
  EXPECT(fs.cell == host_cell);
}

static void enumWidths(void) {
  EXPECT(sizeof(blvd_status) == 4 && sizeof(blvd_backend) == 4 && sizeof(blvd_render_mode) == 4);
  EXPECT(sizeof(blvd_prefetch_priority) == 4 && sizeof(blvd_camera_source) == 4 && sizeof(blvd_gnss_mode) == 4);
  EXPECT(sizeof(blvd_vehicle) == 4 && sizeof(blvd_can_speed_source) == 4);
}

/* A descriptor out of range is refused alike by blvd_memory_required and
 * blvd_runtime_create, for the same reason, before either sizes anything: a
 * ring of two billion events once made memory_required allocate 79 GB. */
static void descriptorsOutOfRange(const char* package) {
  blvd_runtime_desc d;
  blvd_runtime* rt = NULL;
  uint64_t cpu = 0;
  char why[256];
  int k;
  for (k = 0; k < 4; ++k) {
    memset(&d, 0, sizeof d);
    d.package_path = package;
    if (k == 0) d.ring_capacity = 0x7a7a7a7au;
    if (k == 1) d.max_resident_cells = 1;
    if (k == 2) d.prefetch_share = 2.0f;
    if (k == 3) d.mode = (blvd_render_mode)9;
    EXPECT(blvd_memory_required(&d, NULL, &cpu, NULL) == BLVD_ERR_INVALID_ARG);
    EXPECT(strncmp(blvd_last_error(NULL), "blvd_memory_required: ", 22) == 0);
    snprintf(why, sizeof why, "%s", blvd_last_error(NULL) + 22);
    EXPECT(blvd_runtime_create(&d, &rt) == BLVD_ERR_INVALID_ARG && rt == NULL);
    EXPECT(strncmp(blvd_last_error(NULL), "blvd_runtime_create: ", 21) == 0);
    EXPECT(strcmp(blvd_last_error(NULL) + 21, why) == 0);
  }
}

int main(int argc, char** argv) {
  blvd_runtime_desc d;
  blvd_runtime* rt = NULL;
  if (argc < 2) {
    fprintf(stderr, "usage: %s PACKAGE\n", argv[0]);
    return 2;
  }
  nullHandles();
  enumWidths();
  descriptorsOutOfRange(argv[1]);
  memset(&d, 0, sizeof d);
  d.package_path = argv[1];
  d.width = 160;
  d.height = 96;
  if (blvd_runtime_create(&d, &rt) != BLVD_OK) {
    fprintf(stderr, "create: %s\n", blvd_last_error(NULL));
    return 1;
  }
  EXPECT(blvd_set_pose_geo(rt, kLat, kLon, 211.0f, 0.0f) == BLVD_OK);
  EXPECT(blvd_wait_resident(rt, 60000) == BLVD_OK);
  nullArguments(rt, argv[1]);
  outputsStopAtStructSize(rt);
  zeroStructSizes(rt);
  cameraSource(rt);
  blvd_runtime_destroy(rt);
  if (failures) fprintf(stderr, "%d failures\n", failures);
  else printf("API contract: all checks passed\n");
  return failures ? 1 : 0;
}
