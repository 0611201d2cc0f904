/*
 * blvd.h: the whole public C API of blvd (C99). Street-level city rendering for
 * in-vehicle displays and driving simulators.
 *
 * Lifecycle, step by step:
 *   1. Bake a city once, offline:   blvd bake monaco.osm.pbf -o monaco.blvd
 *   2. Fill a blvd_runtime_desc. A zero-initialised descriptor is valid and means
 *      "defaults"; set struct_size = sizeof(blvd_runtime_desc) and package_path.
 *   3. blvd_runtime_create(&desc, &rt): opens the package, creates (or adopts) the
 *      GL context, uploads what it needs. On failure *rt is NULL and
 *      blvd_last_error(NULL) says why, on this thread.
 *   4. Per frame, on the thread that created the runtime:
 *        blvd_set_pose_geo() or blvd_set_pose_local(), then blvd_render(),
 *        then (headless) blvd_read_pixels().
 *   5. blvd_runtime_destroy(rt). destroy(NULL) is a no-op.
 *
 * Conventions:
 *   - Every fallible call returns blvd_status; BLVD_OK is 0. The enum only grows.
 *   - blvd_last_error(rt) is text about the last failed call on rt, valid until the
 *     next call on rt. Nothing throws across this boundary.
 *   - Public structs start with struct_size and only grow at the end.
 *   - Local frame: metres east (x) and north (y) of the package origin.
 *   - Headings: degrees clockwise from true north. Pitch: degrees, up positive.
 */
#ifndef BLVD_H
#define BLVD_H

#include <stddef.h>
#include <stdint.h>

#if defined(_WIN32)
#define BLVD_API __declspec(dllimport)
#elif defined(__GNUC__)
#define BLVD_API __attribute__((visibility("default")))
#else
#define BLVD_API
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* ---- version ---------------------------------------------------------------
 * BLVD_VERSION_NUMBER is the version this header belongs to; compare it with
 * blvd_version_number() to detect a header/library mismatch. */
#define BLVD_VERSION_MAJOR 0
#define BLVD_VERSION_MINOR 1
#define BLVD_VERSION_PATCH 0
#define BLVD_VERSION_NUMBER (BLVD_VERSION_MAJOR * 1000000 + BLVD_VERSION_MINOR * 1000 + BLVD_VERSION_PATCH)

/* Version of the linked library, encoded like BLVD_VERSION_NUMBER. Any thread. */
BLVD_API uint32_t blvd_version_number(void);
/* Version of the linked library as "major.minor.patch". Static storage. Any thread. */
BLVD_API const char* blvd_version_string(void);

/* ---- status ---------------------------------------------------------------- */
typedef enum blvd_status {
  BLVD_OK = 0,
  BLVD_ERR_MISUSE = 1,      /* NULL handle, wrong call order, wrong thread */
  BLVD_ERR_INVALID_ARG = 2, /* an argument or descriptor field is out of range */
  BLVD_ERR_IO = 3,          /* a file cannot be opened or read */
  BLVD_ERR_CORRUPT = 4,     /* the package is truncated, corrupt or foreign */
  BLVD_ERR_NOMEM = 5,       /* an allocation failed */
  BLVD_ERR_BACKEND = 6,     /* no GL context backend could be created */
  BLVD_ERR_BUDGET = 7,      /* the memory budget is too small for the package */
  BLVD_ERR_UNSUPPORTED = 8, /* valid request this build cannot serve */
  BLVD_ERR_INTERNAL = 9,    /* a bug in blvd; please report it */
  BLVD_ERR_NOT_FOUND = 10,  /* the requested item does not exist */
  BLVD_STATUS_FORCE_32 = 0x7fffffff
} blvd_status;

/* Static English text for a status. Never NULL. Any thread. */
BLVD_API const char* blvd_status_string(blvd_status status);

/* ---- runtime ----------------------------------------------------------------- */
typedef struct blvd_runtime blvd_runtime; /* opaque */

typedef enum blvd_backend {
  BLVD_BACKEND_AUTO = 0,           /* try EGL surfaceless, EGL device, then OSMesa */
  BLVD_BACKEND_EGL_SURFACELESS = 1,/* EGL_MESA_platform_surfaceless, off-screen */
  BLVD_BACKEND_EGL_DEVICE = 2,     /* EGL_EXT_platform_device, off-screen */
  BLVD_BACKEND_OSMESA = 3,         /* Mesa's pure-software off-screen GL */
  BLVD_CONTEXT_SHARED = 4,         /* the host's GL context, current on the calling thread */
  BLVD_BACKEND_FORCE_32 = 0x7fffffff
} blvd_backend;

/* What a frame draws. BLVD_MODE_BLVD is the method: the current cell's local
 * blocks as geometry plus its multi-layer impostors for everything farther. The
 * others exist to compare against it. */
typedef enum blvd_render_mode {
  BLVD_MODE_BLVD = 0,    /* local blocks + layered impostors (default) */
  BLVD_MODE_FULL = 1,    /* every block, frustum-culled: the reference */
  BLVD_MODE_LOCAL = 2,   /* the cell's local blocks only */
  BLVD_MODE_RADIUS = 3,  /* blocks within radius_m of the eye (visibility-radius baseline) */
  BLVD_MODE_SINGLE = 4,  /* local blocks + one impostor mesh per cell (Sillion 97) */
  BLVD_MODE_FORCE_32 = 0x7fffffff
} blvd_render_mode;

typedef struct blvd_runtime_desc {
  uint32_t struct_size;     /* sizeof(blvd_runtime_desc); 0 is treated as the current size */
  const char* package_path; /* required: a .blvd file made by `blvd bake`; copied */
  uint32_t width;           /* frame width in pixels; 0 means 800 */
  uint32_t height;          /* frame height in pixels; 0 means 480 */
  blvd_backend backend;     /* 0 means BLVD_BACKEND_AUTO */
  float fov_y_deg;          /* vertical field of view; 0 means 45 */
  float eye_height_m;       /* eye height above the street; 0 means 1.5 */
  float far_m;              /* far clip distance; 0 means 3000 */
  blvd_render_mode mode;    /* 0 means BLVD_MODE_BLVD (falls back to FULL if the package has no impostors) */
  float radius_m;           /* for BLVD_MODE_RADIUS; 0 means 250 */
} blvd_runtime_desc;

/* Returns `desc` with every zero field replaced by its default. Any thread. */
BLVD_API blvd_runtime_desc blvd_runtime_desc_defaults(const blvd_runtime_desc* desc);

/* Creates a runtime. Ownership: the caller owns *out and frees it with
 * blvd_runtime_destroy. Thread: the calling thread becomes the render thread.
 * Errors: BLVD_ERR_INVALID_ARG, BLVD_ERR_IO, BLVD_ERR_CORRUPT, BLVD_ERR_BACKEND;
 * on error *out is NULL and blvd_last_error(NULL) gives the reason. */
BLVD_API blvd_status blvd_runtime_create(const blvd_runtime_desc* desc, blvd_runtime** out);

/* Destroys a runtime and its GL objects. NULL is a no-op. Render thread only. */
BLVD_API void blvd_runtime_destroy(blvd_runtime* rt);

/* Text about the last failed call on rt (or, for rt == NULL, the last failed
 * create on this thread). Valid until the next call on rt. Never NULL. */
BLVD_API const char* blvd_last_error(const blvd_runtime* rt);

typedef struct blvd_runtime_info {
  uint32_t struct_size;  /* set by the caller to sizeof(blvd_runtime_info) */
  const char* backend;   /* "egl-surfaceless", "egl-device", "osmesa" or "shared" */
  const char* gl_renderer; /* GL_RENDERER string */
  const char* gl_version;  /* GL_VERSION string */
  double origin_lat, origin_lon; /* package origin, degrees */
  uint32_t cell_count, block_count, building_count;
  uint64_t triangle_count;       /* triangles in the whole package (full model) */
} blvd_runtime_info;

/* Fills *info. Strings are owned by rt and live as long as it. */
BLVD_API blvd_status blvd_runtime_get_info(blvd_runtime* rt, blvd_runtime_info* info);

/* ---- pose and frames ------------------------------------------------------------ */

/* Places the eye at lat/lon (WGS84 degrees), eye_height_m above the street,
 * looking along heading_deg (clockwise from north), pitched by pitch_deg.
 * Errors: BLVD_ERR_INVALID_ARG for non-finite or out-of-range values. */
BLVD_API blvd_status blvd_set_pose_geo(blvd_runtime* rt, double lat, double lon, float heading_deg,
                                       float pitch_deg);

/* As blvd_set_pose_geo, with x east and y north in metres of the local frame. */
BLVD_API blvd_status blvd_set_pose_local(blvd_runtime* rt, double x, double y, float heading_deg,
                                         float pitch_deg);

typedef struct blvd_frame_stats {
  uint32_t struct_size;
  double frame_ms;    /* CPU+GPU time of the last blvd_render, glFinish included */
  uint64_t triangles; /* triangles submitted by the last blvd_render */
  uint32_t draw_calls;
  uint32_t cell;            /* the cell the pose was matched to (UINT32_MAX: none) */
  uint32_t impostor_layers; /* impostor meshes drawn */
  uint32_t blocks_drawn;    /* block meshes submitted (before frustum culling) */
} blvd_frame_stats;

/* Switches what frames draw (see blvd_render_mode). radius_m is used by
 * BLVD_MODE_RADIUS (0 means 250). Errors: BLVD_ERR_INVALID_ARG for an unknown
 * mode; BLVD_ERR_UNSUPPORTED for BLVD/SINGLE on a package baked without those
 * impostors. Render thread only. */
BLVD_API blvd_status blvd_set_render_mode(blvd_runtime* rt, blvd_render_mode mode, float radius_m);

/* Renders one frame of the current render mode at the current pose into the runtime's
 * framebuffer (or the host's, with BLVD_CONTEXT_SHARED). Render thread only. */
BLVD_API blvd_status blvd_render(blvd_runtime* rt, blvd_frame_stats* stats /* may be NULL */);

/* Copies the last frame as tightly packed RGBA8, top row first, into `rgba`
 * (at least width*height*4 bytes). Errors: BLVD_ERR_INVALID_ARG if too small. */
BLVD_API blvd_status blvd_read_pixels(blvd_runtime* rt, void* rgba, size_t rgba_bytes);

#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* BLVD_H */
