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
 * Conventions (every function follows them; tests/capi checks each from C):
 *   - Every fallible call returns blvd_status; BLVD_OK is 0. The enum only grows.
 *   - A NULL handle (blvd_runtime*, blvd_tracker*, blvd_can_profile*) is
 *     BLVD_ERR_MISUSE; a NULL pointer argument is BLVD_ERR_INVALID_ARG. Destroy
 *     functions take NULL as a no-op.
 *   - blvd_last_error(rt) is text about the last failed call on rt, valid until the
 *     next call on rt. Nothing throws across this boundary.
 *   - Public structs start with struct_size and only grow at the end. Input
 *     structs: struct_size 0 means this header's size; a host built against an
 *     older, shorter struct passes its size, and the fields past it take their
 *     defaults, or, where a struct has no default for a field it misses (the
 *     odometry calibration, the start pose), the call is refused with
 *     BLVD_ERR_INVALID_ARG. Output structs: blvd writes struct_size bytes (0:
 *     this header's size) and nothing past them.
 *   - Each function says on which thread it may be called: "any thread", the
 *     "render thread" (the one that created the runtime), or a tracker's
 *     "tracking thread" (one thread of the host's choice).
 *   - Every enum has a *_FORCE_32 value so that it is 32 bits wide in every ABI.
 *   - Local frame: metres east (x) and north (y) of the package origin.
 *   - Headings: degrees clockwise from true north. Pitch: degrees, up positive.
 */
#ifndef BLVD_H
#define BLVD_H

#include <stddef.h>
#include <stdint.h>

#if defined(_WIN32) && defined(BLVD_BUILDING_LIBRARY)
#define BLVD_API __declspec(dllexport)
#elif defined(_WIN32)
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
  BLVD_ERR_TIMEOUT = 11,    /* a wait ended before its condition held */
  BLVD_ERR_UNAVAILABLE = 12,/* data not here now: offline, or the link is down; try again later */
  BLVD_ERR_OFF_MAP = 13,    /* a pose farther than BLVD_MAP_MARGIN_M outside the package's streets */
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

/* Host allocator for blvd's pools (all taken in blvd_runtime_create). alloc
 * returns memory aligned to `align` or NULL; free takes what alloc returned. */
typedef struct blvd_allocator {
  void* (*alloc)(size_t size, size_t align, void* user);
  void (*free)(void* ptr, void* user);
  void* user;
} blvd_allocator;

/* A host executor for blvd's background work (decoding cells). blvd calls
 * submit(task, task_arg, user) from the render thread; the host must run
 * task(task_arg) exactly once, soon, on a thread other than the render thread:
 * blvd_runtime_destroy waits for every submitted task to have run.
 * submit == NULL: blvd starts its own loader thread. */
typedef struct blvd_executor {
  void (*submit)(void (*task)(void* task_arg), void* task_arg, void* user);
  void* user;
} blvd_executor;

/* Thread priority of predicted cells' decoding (blvd_runtime_desc.prefetch_priority). */
typedef enum blvd_prefetch_priority {
  /* SCHED_IDLE: only on a core nothing else wants, so predictions never take CPU from a frame (the
   * default; nice 19 where the policy is refused). On a CPU the host keeps saturated they then
   * wait, and a cell is decoded only once it is current. */
  BLVD_PREFETCH_IDLE = 0,
  /* nice 19 (SCHED_OTHER): predictions take a small share of a saturated CPU, and a waking decoder
   * may delay a frame. For hosts that keep every core busy. */
  BLVD_PREFETCH_LOW = 1,
  /* SCHED_IDLE, but started without regard to the frames. By default (IDLE) a host that leaves
   * gaps between its frames (drawing at a display's refresh) gets each predicted mesh started in
   * such a gap, when its measured cost fits before the next frame of any runtime in the process;
   * a host that draws back to back is not affected. This value turns that off. */
  BLVD_PREFETCH_IDLE_ANYTIME = 2,
  BLVD_PREFETCH_FORCE_32 = 0x7fffffff
} blvd_prefetch_priority;

typedef struct blvd_runtime_desc {
  uint32_t struct_size;     /* sizeof(blvd_runtime_desc); 0 is treated as the current size */
  const char* package_path; /* required: a .blvd file made by `blvd bake`, or its http:// or https://
                             * URL (see cache_path below); copied */
  uint32_t width;           /* frame width in pixels; 0 means 800 */
  uint32_t height;          /* frame height in pixels; 0 means 480 */
  blvd_backend backend;     /* 0 means BLVD_BACKEND_AUTO */
  float fov_y_deg;          /* vertical field of view; 0 means 45 */
  float eye_height_m;       /* eye height above the street; 0 means 1.5 */
  float far_m;              /* far clip distance; 0 means 3000 */
  blvd_render_mode mode;    /* 0 means BLVD_MODE_BLVD (falls back to FULL if the package has no impostors) */
  float radius_m;           /* for BLVD_MODE_RADIUS; 0 means 250 */

  /* ---- fixed memory. Every pool is carved at create from these
   * and the package's largest cell; nothing grows afterwards. ---- */
  uint64_t memory_budget_bytes; /* CPU bytes for staging, tables, tracking; 0 means 256 MiB */
  uint64_t gpu_budget_bytes;    /* GL buffer and texture bytes; 0 means 512 MiB */
  uint32_t max_resident_cells;  /* cell slots (current + predicted); 0 means 4, at least 2 */
  float upload_budget_ms;       /* GL upload time per frame; 0 means 2 */
  uint32_t ring_capacity;       /* tracking events between two frames; 0 means 512 */
  uint32_t route_capacity;      /* cells a blvd_set_route() may hold; 0 means 4096 */
  blvd_allocator allocator;     /* host allocator for the pools; alloc == NULL means the C heap */

  /* ---- level of detail ---- */
  float target_frame_ms; /* frame-time target: a polygon budget from the frame-time history is shared
                          * by coverage across the blocks' LOD chains (Marvie). 0: no budget, each
                          * block takes its coarsest level within lod_error_px */
  float lod_error_px;    /* without a target: the screen-space error a level may show; 0 means 1 */

  blvd_executor executor; /* host task executor for cell decoding; submit == NULL: blvd's own thread */

  /* With target_frame_ms: the lowest render scale the budget may use once every visible block is at
   * its coarsest level and the frame still misses the target (a fill-bound GPU). The view is then
   * drawn at scale x size pixels and stretched over the viewport; only colour reaches a host's
   * framebuffer (its depth buffer is left alone). Costs one more width x height RGBA8 + depth24
   * framebuffer. 0 means 1: never scale. Within [0.25, 1]. */
  float min_render_scale;

  /* How blvd's own loader decodes predicted cells (the cell the vehicle is in always decodes at
   * normal priority, and takes over a prediction that becomes current). With a host executor the
   * host decides. */
  uint32_t prefetch_priority; /* a blvd_prefetch_priority; 0 means BLVD_PREFETCH_IDLE */

  /* CPUs of blvd's prediction thread (bit i: CPU i). 0 means: every CPU the creating thread may use
   * except the one the render thread runs on, followed each frame (a runnable prediction on the
   * render thread's CPU keeps it from idling while the render thread waits for the GPU or a CPU
   * rasterizer's threads, and only an idle CPU pulls a thread queued on another one;
   * blvd_stats.prefetch_kept_off_cpu says which). Non-zero pins the thread to these CPUs, within the
   * creating thread's, and nothing moves it: for hosts that place their own threads. No effect with a
   * host executor. A mask naming none of the creating thread's CPUs fails create with
   * BLVD_ERR_INVALID_ARG. */
  uint64_t prefetch_cpu_mask;

  /* The most of the wall time that predicted cells' decoding may take, for blvd's prediction threads
   * of every runtime in the process together: a token bucket holding at most 0.25 ms, charged with
   * each predicted mesh's CPU time. A host drawing back to back on a CPU renderer has no idle core,
   * so a cell decoded at once lands in the frame that entered the cell; bounded, it is spread over
   * the frames after. 0 means 0.1; within (0, 1], or negative for no bound. The current cell is never
   * held back, and no mesh waits more than 100 ms. No effect with a host executor. */
  float prefetch_share;

  /* Neighbouring cells share most of their local blocks. A block another resident cell already
   * holds is copied GPU to GPU
   * (glCopyBufferSubData, within upload_budget_ms) into the new cell's slab instead of being read
   * and decoded again; the source cell is not released until the copy is done. 0 or positive: on
   * (the default); negative: off, every cell decodes all its blocks. */
  int32_t block_reuse;

  /* ---- a package on a server (package_path an http:// or https:// URL) ----
   * HTTP range requests fetch the header and directory (the first 16 KiB), the tables (graph,
   * cells, blocks, visibility: written to a mirror in cache_path, read as from a local file) and
   * then one cell's blobs at a time, neighbours in one request, into a disk cache of at most
   * cache_bytes, keyed by the package's content (header and directory CRC), never by URL. Every
   * blob is CRC-checked before it is cached and before it is used. A cell whose data is not there
   * never blocks a frame: the frame is flagged BLVD_FRAME_DEGRADED and draws what is resident,
   * and the cell is asked for again. A package replaced on the server is noticed (ETag, If-Match):
   * blvd_stats.package_changed becomes 1, cached cells keep drawing, nothing of the new one is
   * mixed in; the next create fetches the new package and rebuilds the cache. One process at a
   * time per cache folder. */
  const char* cache_path;        /* folder of the table mirror and blob cache; NULL means
                                  * $XDG_CACHE_HOME/blvd, else $HOME/.cache/blvd, else /tmp/blvd-cache */
  uint64_t cache_bytes;          /* the most the folder holds, mirror included; 0 means 256 MiB. Below
                                  * the tables plus the largest blob: BLVD_ERR_INVALID_ARG */
  uint64_t link_max_bytes_per_s; /* bandwidth cap of the package's link; 0: none */
  uint32_t link_mode;            /* a blvd_link_mode; 0 means BLVD_LINK_ONLINE */

  uint32_t reserved0; /* ignored: the tail padding of descriptors before impostor_texture */

  /* How each cell slot's atlas holds the impostor images on the GPU: a blvd_impostor_texture; 0 means
   * BLVD_TEXTURE_RGBA8. */
  uint32_t impostor_texture;
} blvd_runtime_desc;

/* What a cell slot's impostor atlas holds a texel as. */
typedef enum blvd_impostor_texture {
  BLVD_TEXTURE_RGBA8 = 0, /* 4 bytes a texel */
  /* ETC2 RGB8 (GL_COMPRESSED_RGB8_ETC2): half a byte a texel, decoded in hardware by every OpenGL ES 3.0
   * device. The loader thread encodes each image after decoding it (more CPU a cell: docs/benchmarks.md),
   * and images are placed on a 32-texel grid. Needs OpenGL ES 3.0 or OpenGL 4.3: create fails with
   * BLVD_ERR_BACKEND on an older desktop context. */
  BLVD_TEXTURE_ETC2 = 1,
  BLVD_TEXTURE_FORCE_32 = 0x7fffffff
} blvd_impostor_texture;

/* What a package on a server may fetch. */
typedef enum blvd_link_mode {
  BLVD_LINK_ONLINE = 0,  /* the current cell and the predicted ones */
  BLVD_LINK_METERED = 1, /* the current cell and the next one only; further predictions from the cache */
  BLVD_LINK_OFFLINE = 2, /* nothing: cached cells only (a start offline opens from the mirror) */
  BLVD_LINK_FORCE_32 = 0x7fffffff
} blvd_link_mode;

/* Switches what a package on a server may fetch (no effect on a local package). Errors:
 * BLVD_ERR_INVALID_ARG for an unknown mode. Render thread. */
BLVD_API blvd_status blvd_set_link_mode(blvd_runtime* rt, blvd_link_mode mode);

/* Returns `desc` with every zero field replaced by its default. Any thread. */
BLVD_API blvd_runtime_desc blvd_runtime_desc_defaults(const blvd_runtime_desc* desc);

/* The exact bytes blvd_runtime_create would carve for `desc` and the package
 * at `package_path` (NULL: desc->package_path): *cpu_bytes is what counts
 * against memory_budget_bytes, *gpu_bytes (may be NULL) against
 * gpu_budget_bytes. Opens the package's tables, creates no GL context. For a
 * package of format 3.1 or later the figure depends on the package's largest
 * cell, not on its size: its tables are read through fixed page caches.
 * The descriptor is checked as blvd_runtime_create checks it.
 * Errors: BLVD_ERR_IO, BLVD_ERR_CORRUPT, BLVD_ERR_INVALID_ARG. Any thread. */
BLVD_API blvd_status blvd_memory_required(const blvd_runtime_desc* desc, const char* package_path,
                                          uint64_t* cpu_bytes, uint64_t* gpu_bytes);

/* Creates a runtime. Ownership: the caller owns *out and frees it with
 * blvd_runtime_destroy. Thread: the calling thread becomes the render thread.
 * Errors: BLVD_ERR_INVALID_ARG, BLVD_ERR_IO, BLVD_ERR_CORRUPT, BLVD_ERR_BACKEND,
 * BLVD_ERR_BUDGET (the plan exceeds a budget: the message says by how much),
 * BLVD_ERR_NOMEM (the host allocator failed, or the GL driver had no memory for the cell slabs); on
 * error *out is NULL and blvd_last_error(NULL) gives the reason. */
BLVD_API blvd_status blvd_runtime_create(const blvd_runtime_desc* desc, blvd_runtime** out);

/* Destroys a runtime and its GL objects. NULL is a no-op. Render thread only. */
BLVD_API void blvd_runtime_destroy(blvd_runtime* rt);

/* Text about the last failed call on rt (or, for rt == NULL, the last failed
 * create on this thread). Valid until the next call on rt. Never NULL. The
 * thread the failed call was made on (the render thread for rt; feeds set no
 * text). */
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

/* Fills *info up to info->struct_size. Strings are owned by rt and live as
 * long as it. Render thread. */
BLVD_API blvd_status blvd_runtime_get_info(blvd_runtime* rt, blvd_runtime_info* info);

/* ---- pose and frames ------------------------------------------------------------ */

/* Who places the camera blvd_render draws from: the host (blvd_set_pose_*,
 * the default) or the tracker (the pose blvd_get_pose gives for the newest
 * fed time, once it is valid; until then the camera stays where it was).
 * Feeding never moves the camera by itself: a host that wants it to follow the
 * vehicle says so here. */
typedef enum blvd_camera_source {
  BLVD_CAMERA_HOST = 0,
  BLVD_CAMERA_TRACKED = 1,
  BLVD_CAMERA_FORCE_32 = 0x7fffffff
} blvd_camera_source;

/* Sets the camera's source. Render thread. Errors: BLVD_ERR_INVALID_ARG for
 * an unknown source. */
BLVD_API blvd_status blvd_set_camera_source(blvd_runtime* rt, blvd_camera_source source);

/* How far outside the bounding box of its streets a pose still counts as on the
 * package's map: a vehicle a block or two past the baked area still sees it. */
#define BLVD_MAP_MARGIN_M 250.0

/* Places the eye at lat/lon (WGS84 degrees), eye_height_m above the street,
 * looking along heading_deg (clockwise from north), pitched by pitch_deg. On
 * a package baked with terrain (blvd bake --dem) the street's height and its
 * grade where the camera is are added: pitch_deg is relative to the road.
 * Render thread. Errors: BLVD_ERR_INVALID_ARG for non-finite or out-of-range
 * values; BLVD_ERR_MISUSE while the camera source is BLVD_CAMERA_TRACKED;
 * BLVD_ERR_OFF_MAP for a pose off the map (the message says how far): the
 * camera is then nowhere, and frames draw sky and ground only, flagged
 * BLVD_FRAME_OFF_MAP, until a pose on the map is set. */
BLVD_API blvd_status blvd_set_pose_geo(blvd_runtime* rt, double lat, double lon, float heading_deg,
                                       float pitch_deg);

/* As blvd_set_pose_geo, with x east and y north in metres of the local frame.
 * Render thread. */
BLVD_API blvd_status blvd_set_pose_local(blvd_runtime* rt, double x, double y, float heading_deg,
                                         float pitch_deg);

/* No cell: a pose off the street graph, or not matched yet. */
#define BLVD_NO_CELL 0xffffffffu

typedef struct blvd_frame_stats {
  uint32_t struct_size;
  double frame_ms;    /* CPU+GPU time of the last blvd_render, glFinish included */
  uint64_t triangles; /* triangles submitted by the last blvd_render */
  uint32_t draw_calls;
  uint32_t cell;            /* the cell the pose was matched to (BLVD_NO_CELL: none) */
  uint32_t impostor_layers; /* impostor meshes drawn */
  uint32_t blocks_drawn;    /* block meshes submitted (before frustum culling) */
  uint32_t flags;           /* BLVD_FRAME_* */
} blvd_frame_stats;

/* Bits of blvd_frame_stats.flags. */
#define BLVD_FRAME_DEGRADED 0x01u /* the current cell was not resident yet: drew what was */
#define BLVD_FRAME_OFF_MAP 0x02u  /* the pose is off the map: sky and ground only, cell BLVD_NO_CELL */

typedef struct blvd_pool_stats {
  uint64_t capacity_bytes;   /* carved at create */
  uint64_t used_bytes;       /* in use now */
  uint64_t high_water_bytes; /* most ever in use */
} blvd_pool_stats;

typedef struct blvd_stats {
  uint32_t struct_size;          /* set by the caller */
  uint32_t resident_cells;       /* cells whose geometry is on the GPU */
  uint32_t max_resident_cells;
  blvd_pool_stats gpu;           /* cell slabs: vertex, index and texture bytes; capacity as the GL
                                  * reports it (buffer sizes, each texture level) where it can */
  blvd_pool_stats staging;       /* the loader's staging arenas */
  blvd_pool_stats decode;        /* the loader's decode scratch (high water only; capacity 0) */
  uint64_t table_bytes;          /* package tables held in memory (their page caches) */
  uint64_t tracking_bytes;       /* tracker rings, filter and matcher */
  uint64_t loads;                /* cells decoded by the loader */
  uint64_t evictions;            /* resident cells released for others */
  uint64_t misses;               /* frames whose current cell was not resident */
  uint64_t load_errors;          /* cells that failed to decode, and blocks left out of a cell because
                                  * their blob failed its checksum (the cell draws without them; see
                                  * blvd_last_error) */
  uint64_t frames;
  double upload_ms;              /* GL upload time of the last frame */
  double upload_ms_max;
  double frame_ms;               /* the last frame */
  uint64_t triangles;            /* the last frame */
  uint64_t polygon_budget;       /* with target_frame_ms: block triangles allowed next frame; else 0 */
  uint64_t block_triangles;      /* triangles of the block levels chosen for the last frame (visible ones) */
  uint32_t budget_unreachable;   /* 1 when even the coarsest levels (and min_render_scale) are predicted
                                  * to miss the target */
  float render_scale;            /* the scale the last frame was drawn at; 1 unless min_render_scale < 1 */
  float frame_aim_ms;            /* with target_frame_ms: the frame time the budget aims for now; below the
                                  * target (down to 0.92x) while frames scatter enough that their p95
                                  * would pass 1.25x the target; else 0 */
  uint64_t prefetch_gap_waits;   /* predicted meshes whose decode waited for a gap between frames */
  double prefetch_gap_wait_ms;   /* their waits in all */
  int32_t prefetch_kept_off_cpu; /* the render thread's CPU, which blvd's prediction thread is kept off
                                  * (within the CPUs it inherited at create) so that the CPU idles when
                                  * the render thread waits; -1 when not applied (one CPU allowed, a host
                                  * executor, or the affinity call refused) */
  uint64_t prefetch_share_waits;  /* predicted meshes held back by blvd_runtime_desc.prefetch_share */
  double prefetch_share_wait_ms;  /* their waits in all */
  double loader_cpu_ms;           /* CPU time spent decoding the current cell (not resident when it
                                   * became current), and ... */
  double prefetch_cpu_ms;         /* ... decoding predictions: the loader threads' CPU clocks, or with
                                   * a host executor its tasks' meshes; since create */
  uint64_t blocks_reused;         /* blocks copied from another resident cell instead of decoded
                                   * (blvd_runtime_desc.block_reuse) ... */
  uint64_t block_levels_copied;   /* ... and their levels of detail, one mesh each */
  /* A package on a server (zero for a local one): */
  uint64_t link_requests;         /* HTTP requests, retries included */
  uint64_t link_bytes;            /* body bytes received */
  double link_bytes_per_s;        /* throughput of recent fetches (0 until one) */
  uint64_t cache_hits;            /* blobs served from the disk cache ... */
  uint64_t cache_misses;          /* ... and not found there */
  uint64_t cache_bytes;           /* on disk now, table mirror included: never above cache_bytes */
  uint64_t link_waits;            /* cell loads whose data was not available (offline, link down): asked
                                   * for again after 2 s, not counted in load_errors; and frames drawn
                                   * degraded because the map of where the vehicle is had not arrived */
  uint32_t package_changed;       /* 1: the package on the server was replaced since create */
  double cached_ahead_m;          /* road ahead along the route (the current cell's rest included) whose
                                   * cells are all in the disk cache: divided by the speed, the seconds a
                                   * drive can go without the link */
  double prefetch_horizon_m;      /* how far ahead the link prefetch fetches: the speed times 30 s plus
                                   * twice a cell's fetch time at the measured throughput, at least 400 m */
  double cached_ahead_s;          /* cached_ahead_m at the vehicle's speed (0 when it has none) */
  uint64_t link_table_bytes;      /* of link_bytes, the tables' (header, directory, table pages, blob index) */
  uint64_t cache_evictions;       /* blobs the disk cache evicted to make room */
  /* A package with terrain (its TERR tiles, drawn beyond the blocks): */
  uint64_t terrain_bytes;         /* the tiles' load scratch and slot tables; blvd_memory_required's CPU
                                   * bytes are staging capacity + table_bytes + tracking_bytes + this */
  uint32_t terrain_tiles;         /* tiles drawn by the last frame */
  uint64_t terrain_loads;         /* tiles loaded into their GPU slots */
  uint64_t terrain_load_errors;   /* tiles that failed to load (bad blob, file cut short), not asked for again */
} blvd_stats;

/* Fills *stats up to stats->struct_size. Render thread. */
BLVD_API blvd_status blvd_runtime_stats(blvd_runtime* rt, blvd_stats* stats);

/* Blocks until the cell at the current pose is resident (loading and
 * uploading without the per-frame upload budget), for start-up, tests and
 * benchmarks; blvd_render itself never waits. Errors: BLVD_ERR_TIMEOUT after
 * timeout_ms; BLVD_ERR_CORRUPT when the cell's data fails to decode.
 * Render thread. */
BLVD_API blvd_status blvd_wait_resident(blvd_runtime* rt, double timeout_ms);

/* Sets the route the vehicle will follow (cells in driving order): residency
 * then prefetches along it instead of guessing from successors. n == 0 clears
 * it. Errors: BLVD_ERR_INVALID_ARG for a cell out of range or more than
 * route_capacity cells. Render thread. */
BLVD_API blvd_status blvd_set_route(blvd_runtime* rt, const uint32_t* cells, size_t n);

/* Switches what frames draw (see blvd_render_mode). radius_m is used by
 * BLVD_MODE_RADIUS (0 means 250). Errors: BLVD_ERR_INVALID_ARG for an unknown
 * mode; BLVD_ERR_UNSUPPORTED for BLVD/SINGLE on a package baked without those
 * impostors. Render thread only. */
BLVD_API blvd_status blvd_set_render_mode(blvd_runtime* rt, blvd_render_mode mode, float radius_m);

/* Renders one frame of the current render mode at the current pose into the runtime's
 * framebuffer (or the host's, with BLVD_CONTEXT_SHARED). Render thread only. */
BLVD_API blvd_status blvd_render(blvd_runtime* rt, blvd_frame_stats* stats /* may be NULL */);

/* One view of a multi-view frame: a rectangle of the frame seen from the pose
 * turned, tilted and shifted (a rear-view mirror, a stereo eye). */
#define BLVD_VIEW_MIRROR 0x01u /* left-right flipped, as a mirror shows it */

typedef struct blvd_view {
  uint32_t struct_size;     /* sizeof(blvd_view) */
  uint32_t x, y;            /* top-left corner in the frame, pixels (y down) */
  uint32_t width, height;   /* 0 means the frame's */
  float yaw_offset_deg;     /* added to the pose's heading (180: looking back) */
  float pitch_offset_deg;   /* added to the pose's pitch */
  float eye_offset_right_m; /* eye moved to the right of the pose (stereo: -+ half the separation) */
  float fov_y_deg;          /* 0 means the runtime's */
  uint32_t flags;           /* BLVD_VIEW_* */
} blvd_view;

/* Renders `n` views (1..16) of the current pose in one frame, in order (later
 * views draw over earlier ones where they overlap). The views share one draw
 * list, the residency step and the LOD choice; each view clips to its own
 * frustum. `stats` sums the views. Errors: BLVD_ERR_INVALID_ARG for NULL
 * views, n outside 1..16, or a view outside the frame. Render thread. */
BLVD_API blvd_status blvd_render_views(blvd_runtime* rt, const blvd_view* views, uint32_t n,
                                       blvd_frame_stats* stats /* may be NULL */);

/* Copies the last frame as tightly packed RGBA8, top row first, into `rgba`
 * (at least width*height*4 bytes). Render thread. Errors:
 * BLVD_ERR_INVALID_ARG if NULL or too small; BLVD_ERR_MISUSE before the first
 * render or after blvd_read_items. */
BLVD_API blvd_status blvd_read_pixels(blvd_runtime* rt, void* rgba, size_t rgba_bytes);

/* Object ids of the last frame (ground truth for segmentation, and fidelity
 * checks): draws the last frame's draw list again from its pose and writes one
 * id per pixel, top row first, into `ids` (at least width*height of them):
 *   block + 1                 where a block's geometry shows (0-based block id);
 *   BLVD_ITEM_IMPOSTOR | k    where impostor layer k of the cell shows (k >= 1, the
 *                             package's order: pack cell lists them);
 *   0                         where sky or ground shows.
 * The frame's pixels are overwritten: call blvd_read_pixels first (after this
 * call it fails with BLVD_ERR_MISUSE until the next render). Views of
 * blvd_render_views are not repeated: the ids are of the whole frame's
 * camera. Errors: BLVD_ERR_INVALID_ARG if `ids` is too small, BLVD_ERR_MISUSE
 * before the first render. Render thread only. */
#define BLVD_ITEM_IMPOSTOR 0x800000u
BLVD_API blvd_status blvd_read_items(blvd_runtime* rt, uint32_t* ids, size_t count);


/* ---- position tracking ---------------------------------------------------------
 * Feed GNSS fixes and odometry from any thread; blvd fuses them (EKF) and
 * matches the vehicle onto the street graph (HMM, fixed-lag Viterbi). With
 * blvd_set_camera_source(rt, BLVD_CAMERA_TRACKED), blvd_render() draws from
 * the tracked pose. Times are seconds on one clock the host chooses. */

/* Bits of blvd_gnss_fix.flags: which fields hold a value. */
#define BLVD_GNSS_HAS_TIME 0x01u
#define BLVD_GNSS_HAS_LATLON 0x02u
#define BLVD_GNSS_HAS_ALT 0x04u
#define BLVD_GNSS_HAS_SPEED 0x08u
#define BLVD_GNSS_HAS_TRACK 0x10u
#define BLVD_GNSS_HAS_HDOP 0x20u
#define BLVD_GNSS_HAS_HACC 0x40u

/* The fix's dimension, as gpsd's TPV "mode". */
typedef enum blvd_gnss_mode {
  BLVD_GNSS_MODE_UNKNOWN = 0, /* not reported */
  BLVD_GNSS_MODE_NO_FIX = 1,
  BLVD_GNSS_MODE_2D = 2,
  BLVD_GNSS_MODE_3D = 3,
  BLVD_GNSS_MODE_FORCE_32 = 0x7fffffff
} blvd_gnss_mode;

typedef struct blvd_gnss_fix {
  uint32_t struct_size; /* sizeof(blvd_gnss_fix) */
  double t;             /* host clock, seconds, when the position was valid */
  double lat, lon, alt; /* WGS 84 degrees; metres above mean sea level */
  float speed_mps;      /* over ground */
  float track_deg;      /* course over ground, degrees true */
  float hdop;
  float h_acc_m;        /* horizontal accuracy (GST), metres */
  blvd_gnss_mode mode;  /* as gpsd's TPV mode */
  uint32_t flags;       /* BLVD_GNSS_HAS_* */
} blvd_gnss_fix;

/* Bits of blvd_odometry.flags. */
#define BLVD_ODO_SPEED 0x001u
#define BLVD_ODO_YAW_RATE 0x004u
#define BLVD_ODO_WHEEL_SPEEDS 0x010u
#define BLVD_ODO_GEAR 0x020u
#define BLVD_ODO_HEADING 0x100u

typedef struct blvd_odometry {
  uint32_t struct_size;       /* sizeof(blvd_odometry) */
  double t;                   /* host clock, seconds */
  double speed_mps;           /* ground speed, unsigned */
  double yaw_rate_dps;        /* positive to the left (ISO 8855) */
  double wheel_speeds_mps[4]; /* FL, FR, RL, RR */
  double heading_deg;         /* absolute heading, clockwise from north */
  int32_t reverse;            /* gear is reverse (with BLVD_ODO_GEAR) */
  uint32_t flags;             /* BLVD_ODO_* */
} blvd_odometry;

/* Bits of blvd_pose.flags. */
#define BLVD_POSE_VALID 0x01u
#define BLVD_POSE_HEADING_VALID 0x02u
#define BLVD_POSE_MATCHED 0x04u
#define BLVD_POSE_DEAD_RECKONING 0x08u
#define BLVD_POSE_OFF_MAP 0x10u /* the fused position is off the map (BLVD_MAP_MARGIN_M): no cell, no match */

typedef struct blvd_pose {
  uint32_t struct_size;      /* set by the caller */
  double t;                  /* the time it was computed for */
  double x, y;               /* local east / north metres */
  double lat, lon;           /* WGS 84 degrees */
  double heading_deg;        /* clockwise from north */
  double speed_mps;
  uint32_t cell;             /* matched cell (BLVD_NO_CELL: none) */
  double arc_m;              /* distance along the cell */
  double lateral_m;          /* offset from the cell's centre line, right positive */
  double confidence;         /* posterior probability of the matched cell, 0..1 */
  uint32_t flags;            /* BLVD_POSE_* */
  /* The camera blvd_render places for this pose: the eye on the matched street at the driver's
   * height (at the fused position when unmatched), local east / north / up metres. A host that
   * renders a recorded drive later puts the camera here (blvd_set_pose_local). */
  double camera_x, camera_y, camera_z;
  double camera_heading_deg, camera_pitch_deg;
  /* 1-sigma of the fused position (its larger axis, metres) and of the heading (degrees; 0 before
   * the heading is known): what blvd_start_pose wants at the next start. */
  double pos_sigma_m;
  double heading_sigma_deg;
} blvd_pose;

/* Queues a GNSS fix. Any thread; no allocation; sets no last error. Errors:
 * BLVD_ERR_INVALID_ARG for a NULL fix. A full queue drops its oldest entry
 * (counted). */
BLVD_API blvd_status blvd_feed_gnss(blvd_runtime* rt, const blvd_gnss_fix* fix);

/* Queues an odometry sample (speed, yaw rate, wheel speeds, gear, heading from
 * CAN or a simulator). Any thread; no allocation; sets no last error. Errors:
 * BLVD_ERR_INVALID_ARG for a NULL sample. */
BLVD_API blvd_status blvd_feed_odometry(blvd_runtime* rt, const blvd_odometry* odo);

/* Processes what was fed up to time t and writes the tracked pose up to
 * pose->struct_size. Render thread (blvd_render calls it with the newest fed
 * time when the camera source is BLVD_CAMERA_TRACKED). Errors:
 * BLVD_ERR_INVALID_ARG for a NULL pose or a non-finite t. */
BLVD_API blvd_status blvd_get_pose(blvd_runtime* rt, double t, blvd_pose* pose);

/* The odometry's calibration, which the filter learns from GNSS while driving: the wheel-speed
 * scale (tyre radius) and the yaw-rate sensor's bias. They belong to the vehicle, not to the
 * drive: read them at the end of a drive (key-off), store them, and give them back before the
 * next drive's first fix, so that dead reckoning starts calibrated instead of learning them
 * again (as automotive dead reckoning keeps its odometer scale factor in non-volatile memory). */
typedef struct blvd_odometry_calibration {
  uint32_t struct_size;           /* sizeof(blvd_odometry_calibration) */
  double speed_scale;             /* the odometry reads speed_scale x the ground speed; 1 = exact */
  double speed_scale_sigma;       /* its 1-sigma (raised to 0.002 when set: tyre pressure and
                                   * temperature change between drives) */
  double yaw_rate_bias_dps;       /* measured minus true yaw rate, positive to the left */
  double yaw_rate_bias_sigma_dps; /* its 1-sigma (raised to 0.05 when set: a gyro's bias moves
                                   * from one power-up to the next) */
} blvd_odometry_calibration;

/* The current estimate (before the first fix: what the filter will start from). Render thread,
 * as blvd_get_pose: it reflects what blvd_get_pose or blvd_render last processed. */
BLVD_API blvd_status blvd_get_odometry_calibration(blvd_runtime* rt, blvd_odometry_calibration* cal);

/* Starts the filter's scale and bias from `cal` (a running filter takes them at once; a reset
 * keeps them). Render thread. Errors: BLVD_ERR_INVALID_ARG for a scale outside [0.5, 2], a bias
 * beyond 10 deg/s, a negative sigma or a non-finite field; nothing changes then. */
BLVD_API blvd_status blvd_set_odometry_calibration(blvd_runtime* rt, const blvd_odometry_calibration* cal);

/* Where the vehicle was last known to be: the pose read at the end of the previous drive (key-off:
 * blvd_get_pose's lat, lon, heading_deg, pos_sigma_m, heading_sigma_deg), kept by the host in
 * non-volatile memory, as automotive navigation keeps its last position. Given back at the next
 * start (key-on), the drive is tracked from there at once: a matched pose before the first fix,
 * and dead reckoning out of a garage where there is none. Latitude and longitude, so it stays
 * valid when the package is updated between drives. */
typedef struct blvd_start_pose {
  uint32_t struct_size;     /* sizeof(blvd_start_pose) */
  double t;                 /* host clock, seconds: when the vehicle was (still) there, e.g. key-on */
  double lat, lon;          /* WGS 84 degrees */
  double heading_deg;       /* clockwise from north */
  double sigma_m;           /* 1-sigma of the position per axis; 0: 2 m; raised to 0.5 m at least */
  double heading_sigma_deg; /* 0: 5 degrees; raised to 1 degree at least */
} blvd_start_pose;

/* Starts tracking from `sp` instead of waiting for the first fix (a drive under way is forgotten;
 * what was fed and not yet processed is kept); the camera follows it with BLVD_CAMERA_TRACKED.
 * Fixes that disagree with it (the car was moved while parked) are rejected at first and, after
 * five in a row, taken instead. Render thread. Errors: BLVD_ERR_INVALID_ARG for a latitude or
 * longitude out of range, a negative sigma, sigma_m over 10 km or heading_sigma_deg over 180, a
 * heading beyond 720 degrees, a non-finite field or a nonzero struct_size that does not cover
 * heading_sigma_deg; nothing changes then. */
BLVD_API blvd_status blvd_set_start_pose(blvd_runtime* rt, const blvd_start_pose* sp);

/* What tracking made of its input since create: each fault a drive meets is counted here while
 * the drive goes on (a GNSS outage is dead reckoned, a jump gated out, fixes out of order used
 * late, a repeated epoch counted once, a clock that went back restarts from the pose). */
typedef struct blvd_tracking_stats {
  uint32_t struct_size;      /* set by the caller; 0: the whole struct */
  uint64_t gnss_fed;         /* fixes queued by the feeds ... */
  uint64_t odometry_fed;     /* ... and odometry samples (a CAN frame's decoded sample counts once) */
  uint64_t queue_dropped;    /* lost to a full queue, the oldest first (blvd_tracker_desc.ring_capacity) */
  uint64_t gnss_used;        /* positions the filter took */
  uint64_t gnss_rejected;    /* positions gated out: too far from where the filter expects (a jump,
                              * multipath); five in a row reset the position to the fixes' */
  uint64_t gnss_ignored;     /* no fix, no position, or a value out of range */
  uint64_t gnss_duplicates;  /* further reports of an epoch already processed (the same t, as gpsd sends
                              * a report per sentence): the position counts once; a speed or course the
                              * first report lacked is used */
  uint64_t odometry_ignored; /* a time that is not finite */
  uint64_t late;             /* fixes and samples older than the filter when processed (out of order) */
  uint64_t clock_steps;      /* input stamped 30 s or more before the filter (the host clock went back)
                              * or 600 s or more after it (a gap no prediction spans): tracking went
                              * on from the pose under the new time */
  uint64_t filter_resets;    /* positions reset to the fixes after a run of rejected ones */
  uint64_t outages;          /* times dead reckoning began (BLVD_POSE_DEAD_RECKONING) after a fix */
  double longest_outage_s;   /* the longest time without a usable fix, once dead reckoning began */
} blvd_tracking_stats;

/* Fills *stats up to stats->struct_size. Render thread, as blvd_get_pose (it counts what
 * blvd_get_pose or blvd_render last processed). Errors: BLVD_ERR_INVALID_ARG for a NULL stats. */
BLVD_API blvd_status blvd_get_tracking_stats(blvd_runtime* rt, blvd_tracking_stats* stats);

/* ---- CAN frames through a vehicle profile ---------------------------------------
 * A profile reads one vehicle's CAN signals, as its DBC file describes them
 * (opendbc's files), and turns them into odometry: speed, yaw rate, wheel speeds
 * and gear. Use one profile per CAN bus: it holds the latest value of every
 * signal. Typical use:
 *   blvd_can_profile_desc pd = {sizeof pd};  pd.dbc_path = "toyota_new_mc_pt_generated.dbc";
 *   blvd_can_profile_create(&pd, &profile);
 *   per received frame (any thread): blvd_feed_can_frame(rt, profile, &frame);
 *   blvd_can_profile_destroy(profile) after the last feed. */
typedef struct blvd_can_profile blvd_can_profile; /* opaque */

/* Which signals a profile reads (the message and signal names of each are
 * listed in docs/decisions/0005-can-profiles-in-sdk.md). */
typedef enum blvd_vehicle {
  BLVD_VEHICLE_TOYOTA = 0,  /* opendbc toyota_new_mc_pt_generated.dbc (checked on a RAV4 log) */
  BLVD_VEHICLE_VW_MQB = 1,  /* opendbc vw_mqb.dbc */
  BLVD_VEHICLE_HYUNDAI = 2, /* opendbc hyundai_2015_ccan.dbc */
  BLVD_VEHICLE_FORCE_32 = 0x7fffffff
} blvd_vehicle;

/* Where blvd_odometry.speed_mps comes from. */
typedef enum blvd_can_speed_source {
  BLVD_CAN_SPEED_AUTO = 0,    /* the mean wheel speed while fresh, else the vehicle speed signal */
  BLVD_CAN_SPEED_WHEELS = 1,  /* only the mean of the four wheel speeds */
  BLVD_CAN_SPEED_VEHICLE = 2, /* only the vehicle speed signal */
  BLVD_CAN_SPEED_FORCE_32 = 0x7fffffff
} blvd_can_speed_source;

typedef struct blvd_can_profile_desc {
  uint32_t struct_size;        /* sizeof(blvd_can_profile_desc); 0 is treated as the current size */
  blvd_vehicle vehicle;        /* 0 means BLVD_VEHICLE_TOYOTA */
  const char* dbc_path;        /* required: the vehicle's DBC file; read once by create */
  blvd_can_speed_source speed; /* 0 means BLVD_CAN_SPEED_AUTO */
  float wheel_stale_s;         /* AUTO falls back to the vehicle speed after this long; 0 means 0.5 */
  uint32_t flags;              /* BLVD_CAN_PROFILE_*; 0: a DBC message the decoder cannot use is skipped */
} blvd_can_profile_desc;

/* Bits of blvd_can_profile_desc.flags. */
#define BLVD_CAN_PROFILE_STRICT_DBC 0x1u /* such a message fails create instead (BLVD_ERR_CORRUPT, or
                                          * BLVD_ERR_UNSUPPORTED for valid DBC this decoder does not follow) */

/* The vehicle named "toyota", "vw_mqb" or "hyundai". Any thread.
 * Errors: BLVD_ERR_INVALID_ARG for NULL; BLVD_ERR_NOT_FOUND for another name. */
BLVD_API blvd_status blvd_vehicle_from_name(const char* name, blvd_vehicle* out);

/* Reads the DBC and binds the vehicle's signals. Ownership: the caller frees
 * *out with blvd_can_profile_destroy. Thread: any. Memory: allocates the parsed
 * DBC here, nothing afterwards. Errors (*out NULL, blvd_last_error(NULL) says
 * why, naming the file and line or each missing message and signal):
 * BLVD_ERR_INVALID_ARG (also for unknown flags), BLVD_ERR_IO, BLVD_ERR_CORRUPT,
 * BLVD_ERR_UNSUPPORTED (strict only), BLVD_ERR_NOT_FOUND. */
BLVD_API blvd_status blvd_can_profile_create(const blvd_can_profile_desc* desc, blvd_can_profile** out);

/* Frees a profile. NULL is a no-op. No feed may be using it. */
BLVD_API void blvd_can_profile_destroy(blvd_can_profile* profile);

/* The index-th warning of reading the profile's DBC, "file:line: text" (a message
 * skipped, and why; a signal left out), or NULL past the last one. The text lives
 * as long as the profile. Any thread; no allocation. */
BLVD_API const char* blvd_can_profile_warning(const blvd_can_profile* profile, uint32_t index);

/* Bits of blvd_can_frame.flags. */
#define BLVD_CAN_EXTENDED 0x1u /* 29-bit identifier */
#define BLVD_CAN_RTR 0x2u      /* remote transmission request */
#define BLVD_CAN_ERROR 0x4u    /* error frame */
#define BLVD_CAN_FD 0x8u       /* CAN FD frame */

typedef struct blvd_can_frame {
  uint32_t struct_size; /* sizeof(blvd_can_frame); 0 is treated as the current size */
  double t;             /* host clock, seconds (the clock of the other feeds) */
  uint32_t id;          /* identifier without flag bits */
  uint32_t flags;       /* BLVD_CAN_* */
  uint8_t len;          /* payload bytes: 0..8, or a CAN FD length up to 64 */
  uint8_t data[64];
} blvd_can_frame;

/* One message a profile reads, for the host's receive filters (SocketCAN's
 * CAN_RAW_FILTER, a gateway's pass list). */
typedef struct blvd_can_message_id {
  uint32_t id;    /* identifier without flag bits */
  uint32_t flags; /* BLVD_CAN_EXTENDED for a 29-bit identifier, else 0 */
} blvd_can_message_id;

/* The messages the profile reads, in identifier order: *count gets how many
 * there are, and the first min(capacity, *count) go to ids (NULL when capacity
 * is 0: ask for the count first). Any thread; no allocation.
 * Errors: BLVD_ERR_MISUSE for a NULL profile; BLVD_ERR_INVALID_ARG for a NULL
 * count, or NULL ids with a capacity. */
BLVD_API blvd_status blvd_can_profile_message_ids(const blvd_can_profile* profile, blvd_can_message_id* ids,
                                                  uint32_t capacity, uint32_t* count);

/* Decodes one frame through the profile: *odo gets the state after it, its
 * flags the BLVD_ODO_* fields this frame changed. Any thread (the profile
 * locks itself); no allocation. Errors: BLVD_ERR_NOT_FOUND when the frame
 * changed none of the fields blvd_odometry holds (another id, an error or RTR
 * frame, or only the steering angle; *odo untouched); BLVD_ERR_INVALID_ARG
 * for NULL arguments, len > 64, or len > 8 without BLVD_CAN_FD. */
BLVD_API blvd_status blvd_can_profile_decode(blvd_can_profile* profile, const blvd_can_frame* frame,
                                             blvd_odometry* odo);

/* Decodes a frame through the profile and queues what it carried as
 * blvd_feed_odometry does. A frame with none of the profile's signals is
 * ignored (BLVD_OK): pass the whole bus. Any thread; no allocation.
 * Errors: BLVD_ERR_MISUSE for a NULL rt or profile; BLVD_ERR_INVALID_ARG as
 * blvd_can_profile_decode. */
BLVD_API blvd_status blvd_feed_can_frame(blvd_runtime* rt, blvd_can_profile* profile, const blvd_can_frame* frame);

/* ---- Tracking without a renderer -------------------------------------------------
 * A tracker follows the vehicle on a package's street graph from GNSS fixes,
 * odometry and CAN frames, with no GL context and without reading the
 * package's render data (blocks, impostors): for a head unit's navigation
 * logic, a cluster display, a logger or a test bench. It is the tracker a
 * runtime holds (sdk/track): the same feeds give the same poses as
 * blvd_get_pose. Typical use:
 *   blvd_tracker_desc td = {sizeof td};  td.package_path = "monaco.blvd";
 *   blvd_tracker_create(&td, &tr);
 *   any thread:        blvd_tracker_feed_gnss(tr, &fix);  blvd_tracker_feed_odometry(tr, &odo);
 *   tracking thread:   blvd_tracker_get_pose(tr, t, &pose);
 *   at the end:        blvd_tracker_destroy(tr);
 * "Tracking thread" is one thread of the host's choice, the same for every
 * such call on a tracker. */
typedef struct blvd_tracker blvd_tracker; /* opaque */

typedef struct blvd_tracker_desc {
  uint32_t struct_size;          /* sizeof(blvd_tracker_desc); 0 is treated as the current size */
  const char* package_path;      /* the package whose street graph poses are matched on (a path,
                                  * or an http:// or https:// URL as in blvd_runtime_desc); NULL:
                                  * no map matching (fusion and dead reckoning only) */
  double origin_lat, origin_lon; /* without a package: the origin of the local x/y frame
                                  * (WGS 84 degrees); ignored with one (the package's origin) */
  float eye_height_m;            /* blvd_pose.camera_z above the street; 0 means 1.5 */
  uint32_t ring_capacity;        /* feeds held until the next get_pose; 0 means 512 */
  const char* cache_path;        /* a package on a server: as blvd_runtime_desc (its tables only) */
  uint64_t cache_bytes;
  uint64_t link_max_bytes_per_s;
  uint32_t link_mode;
} blvd_tracker_desc;

/* Opens the package's street graph (CRC-checked; nothing else is read) and
 * carves the tracker's memory. Ownership: the caller frees *out with
 * blvd_tracker_destroy. Thread: any. Memory: allocates here, never while
 * feeding or tracking. Errors (*out NULL, blvd_last_error(NULL) says why, naming
 * the file and offset): BLVD_ERR_MISUSE for a NULL desc or out;
 * BLVD_ERR_INVALID_ARG for an origin or field out of range; BLVD_ERR_IO,
 * BLVD_ERR_CORRUPT, BLVD_ERR_UNSUPPORTED for the package. */
BLVD_API blvd_status blvd_tracker_create(const blvd_tracker_desc* desc, blvd_tracker** out);

/* Frees a tracker. NULL is a no-op. No feed may be using it. */
BLVD_API void blvd_tracker_destroy(blvd_tracker* tr);

/* Why the tracker's last call on the tracking thread failed (empty when none);
 * blvd_last_error(NULL) for a failed create. Tracking thread. */
BLVD_API const char* blvd_tracker_last_error(const blvd_tracker* tr);

/* Queue a GNSS fix, an odometry sample, or what a CAN frame carries through a
 * profile (as blvd_feed_gnss, blvd_feed_odometry, blvd_feed_can_frame). Any
 * thread; no allocation; a full queue drops its oldest entry. Errors:
 * BLVD_ERR_MISUSE for a NULL tracker (or profile); BLVD_ERR_INVALID_ARG for
 * a NULL fix, sample or frame, or a frame no CAN bus carries. */
BLVD_API blvd_status blvd_tracker_feed_gnss(blvd_tracker* tr, const blvd_gnss_fix* fix);
BLVD_API blvd_status blvd_tracker_feed_odometry(blvd_tracker* tr, const blvd_odometry* odo);
BLVD_API blvd_status blvd_tracker_feed_can_frame(blvd_tracker* tr, blvd_can_profile* profile,
                                                 const blvd_can_frame* frame);

/* Processes what was fed up to time t and returns the tracked pose (x/y in
 * the package's local frame, or the origin's without one). Tracking thread.
 * Errors: BLVD_ERR_MISUSE for a NULL tracker; BLVD_ERR_INVALID_ARG for a NULL
 * pose or a non-finite t. */
BLVD_API blvd_status blvd_tracker_get_pose(blvd_tracker* tr, double t, blvd_pose* pose);

/* As blvd_get_odometry_calibration, blvd_set_odometry_calibration and
 * blvd_set_start_pose, on a tracker. Tracking thread. */
BLVD_API blvd_status blvd_tracker_get_odometry_calibration(blvd_tracker* tr, blvd_odometry_calibration* cal);
BLVD_API blvd_status blvd_tracker_set_odometry_calibration(blvd_tracker* tr, const blvd_odometry_calibration* cal);
BLVD_API blvd_status blvd_tracker_set_start_pose(blvd_tracker* tr, const blvd_start_pose* sp);

/* As blvd_get_tracking_stats, on a tracker. Tracking thread. */
BLVD_API blvd_status blvd_tracker_get_stats(blvd_tracker* tr, blvd_tracking_stats* stats);

#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* BLVD_H */
