/*
 * embree_trace.c -- trace a ray-set directory (see ../embree_rays.py for the format)
 * with Embree 4, loaded at run time with dlopen (no Embree headers needed).
 *
 *   embree_trace DIR --lib PATH [--threads T] [--passes P] [--no-write]
 *                    [--sets primary,diffuse,shadow] [--build-threads N]
 *                    [--name embree] [--device-config STR] [--quality Q] [--packet W]
 *
 * DIR/triangles.f32             f32 LE, 9 per triangle (v0.xyz v1.xyz v2.xyz)
 * DIR/{primary,diffuse}.rays    f32 LE, 8 per ray (ox oy oz dx dy dz tmin tmax): closest hit
 * DIR/shadow.rays               same layout: occlusion query (any hit in [tmin, tmax])
 * writes DIR/<set>.<name>.hits  16 bytes per ray: u32 prim (0xFFFFFFFF = miss), f32 t, u, v
 *                               (u, v: hit = (1-u-v) v0 + u v1 + v v2; miss: t = u = v = NaN;
 *                               shadow: prim 0 = occluded, 0xFFFFFFFF = free, t = u = v = NaN)
 * prints one JSON line on stdout.
 *
 * Timing: build = wall time of rtcCommitScene (CLOCK_MONOTONIC), after device creation and
 * after a warm-up commit of a small throw-away scene (so TBB's worker start-up is not
 * counted). Each set is traced --passes times; the fastest pass counts. A pass: T threads
 * (the main thread + T-1 pthreads created once, parked on a barrier between passes) take
 * chunks of 1024 rays from an atomic counter; each ray's record is stored in an in-memory
 * array in every pass; the file is written after the last pass (not timed).
 *
 * --packet W (4, 8 or 16) traces W consecutive rays at once (rtcIntersectW/rtcOccludedW,
 * structure-of-arrays packets, the last one masked): the calls Mitsuba 3's LLVM variants
 * make, W being their vector width (16 with AVX-512, 8 with AVX2). Default 1: single rays.
 *
 * Build: gcc -O2 -std=c11 -Wall -Wextra -pthread -o build/embree_trace embree_trace.c -ldl -lm
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

/* ---------------------------------------------------------------------------------------
 * The subset of the Embree 4 C API used here (embree4/rtcore_*.h). Values checked against
 * the 4.x headers: enums are plain C ints, handles opaque pointers.
 * ------------------------------------------------------------------------------------- */
typedef void *RTCDevice;
typedef void *RTCScene;
typedef void *RTCGeometry;

enum { RTC_GEOMETRY_TYPE_TRIANGLE = 0 };
enum { RTC_BUFFER_TYPE_INDEX = 0, RTC_BUFFER_TYPE_VERTEX = 1 };
enum { RTC_FORMAT_UINT3 = 0x5003, RTC_FORMAT_FLOAT3 = 0x9003 };
enum {
    RTC_DEVICE_PROPERTY_VERSION = 0,
    RTC_DEVICE_PROPERTY_BACKFACE_CULLING_ENABLED = 65,
    RTC_DEVICE_PROPERTY_TASKING_SYSTEM = 128,
};
#define RTC_INVALID_GEOMETRY_ID 0xFFFFFFFFu

/* struct RTC_ALIGN(16) RTCRay (rtcore_ray.h): 48 bytes */
typedef struct __attribute__((aligned(16))) {
    float org_x, org_y, org_z, tnear;
    float dir_x, dir_y, dir_z, time;
    float tfar;
    unsigned int mask, id, flags;
} RTCRay;

/* struct RTC_ALIGN(16) RTCHit: Ng, u, v, primID, geomID, instID[RTC_MAX_INSTANCE_LEVEL_COUNT]
 * and, when the library was built with RTC_GEOMETRY_INSTANCE_ARRAY (4.3+),
 * instPrimID[RTC_MAX_INSTANCE_LEVEL_COUNT]. The level count is 1 by default; the spare
 * words leave room for builds with more instance levels and/or instPrimID, so Embree
 * never writes past the end of this struct whatever its configuration. */
typedef struct __attribute__((aligned(16))) {
    float Ng_x, Ng_y, Ng_z;
    float u, v;
    unsigned int primID, geomID;
    unsigned int instID[1];
    unsigned int spare[24]; /* instPrimID[] and/or further instance levels */
} RTCHit;

typedef struct {
    RTCRay ray;
    RTCHit hit;
} RTCRayHit;

_Static_assert(sizeof(RTCRay) == 48, "RTCRay must be 48 bytes");
_Static_assert(offsetof(RTCRay, tfar) == 32, "RTCRay.tfar at 32");
_Static_assert(offsetof(RTCRayHit, hit) == 48, "RTCRayHit.hit at 48");
_Static_assert(offsetof(RTCHit, primID) == 20, "RTCHit.primID at 20");
_Static_assert(offsetof(RTCHit, instID) == 28, "RTCHit.instID at 28");

/* Packets of W rays (RTCRayW, RTCHitW, RTCRayHitW of rtcore_ray.h): each field an array
 * of W; aligned to 4 W bytes. The hit's spare words play the same part as RTCHit's. */
#define DEFINE_PACKET(W)                                                                    \
    typedef struct __attribute__((aligned(4 * W))) {                                        \
        float org_x[W], org_y[W], org_z[W], tnear[W];                                        \
        float dir_x[W], dir_y[W], dir_z[W], time[W];                                         \
        float tfar[W];                                                                       \
        unsigned int mask[W], id[W], flags[W];                                               \
    } RTCRay##W;                                                                             \
    typedef struct __attribute__((aligned(4 * W))) {                                        \
        float Ng_x[W], Ng_y[W], Ng_z[W];                                                     \
        float u[W], v[W];                                                                    \
        unsigned int primID[W], geomID[W];                                                   \
        unsigned int instID[1][W];                                                           \
        unsigned int spare[24][W];                                                           \
    } RTCHit##W;                                                                             \
    typedef struct {                                                                         \
        RTCRay##W ray;                                                                       \
        RTCHit##W hit;                                                                       \
    } RTCRayHit##W;
DEFINE_PACKET(4)
DEFINE_PACKET(8)
DEFINE_PACKET(16)
_Static_assert(offsetof(RTCRayHit16, hit) == 12 * 64, "RTCRayHit16.hit after 12 arrays of 16");

typedef void (*RTCErrorFunction)(void *userPtr, int code, const char *str);

static struct {
    RTCDevice (*NewDevice)(const char *config);
    void (*ReleaseDevice)(RTCDevice);
    int (*GetDeviceError)(RTCDevice);
    const char *(*GetDeviceLastErrorMessage)(RTCDevice); /* optional (4.3+) */
    void (*SetDeviceErrorFunction)(RTCDevice, RTCErrorFunction, void *);
    ptrdiff_t (*GetDeviceProperty)(RTCDevice, int prop);
    RTCScene (*NewScene)(RTCDevice);
    void (*ReleaseScene)(RTCScene);
    void (*CommitScene)(RTCScene);
    RTCGeometry (*NewGeometry)(RTCDevice, int type);
    void (*ReleaseGeometry)(RTCGeometry);
    void (*CommitGeometry)(RTCGeometry);
    unsigned int (*AttachGeometry)(RTCScene, RTCGeometry);
    void *(*SetNewGeometryBuffer)(RTCGeometry, int type, unsigned int slot, int format,
                                  size_t byteStride, size_t itemCount);
    void (*Intersect1)(RTCScene, RTCRayHit *, void *args);
    void (*Occluded1)(RTCScene, RTCRay *, void *args);
    /* rtcIntersectW / rtcOccludedW (const int *valid, scene, packet, args), W = 4, 8, 16 */
    void (*Intersect4)(const int *, RTCScene, RTCRayHit4 *, void *args);
    void (*Occluded4)(const int *, RTCScene, RTCRay4 *, void *args);
    void (*Intersect8)(const int *, RTCScene, RTCRayHit8 *, void *args);
    void (*Occluded8)(const int *, RTCScene, RTCRay8 *, void *args);
    void (*Intersect16)(const int *, RTCScene, RTCRayHit16 *, void *args);
    void (*Occluded16)(const int *, RTCScene, RTCRay16 *, void *args);
    /* enum RTCBuildQuality: 0 low, 1 medium (the default), 2 high (spatial splits) */
    void (*SetSceneBuildQuality)(RTCScene, int quality);
    void (*SetGeometryBuildQuality)(RTCGeometry, int quality);
} rtc;

/* The build quality asked for by --quality (1: Embree's default, medium). */
static int g_quality = 1;
/* Rays per call (--packet): 1, 4, 8 or 16. */
static int g_packet = 1;

/* ------------------------------------------------------------------------------------- */

static void die(const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    fputs("embree_trace: error: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
    exit(1);
}

static double now_ms(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

static void *xmalloc(size_t n) {
    void *p = NULL;
    if (posix_memalign(&p, 64, n ? n : 64) != 0) die("out of memory (%zu bytes)", n);
    return p;
}

/* Reads a whole file whose size must be a multiple of `record` bytes. */
static void *read_records(const char *path, size_t record, size_t *count) {
    FILE *f = fopen(path, "rb");
    if (!f) die("cannot open %s: %s", path, strerror(errno));
    struct stat st;
    if (fstat(fileno(f), &st) != 0) die("cannot stat %s: %s", path, strerror(errno));
    size_t size = (size_t)st.st_size;
    if (size % record != 0)
        die("%s: size %zu bytes is not a multiple of the %zu-byte record", path, size, record);
    void *buf = xmalloc(size);
    if (size && fread(buf, 1, size, f) != size) die("short read on %s", path);
    fclose(f);
    *count = size / record;
    return buf;
}

static void write_file(const char *path, const void *data, size_t size) {
    FILE *f = fopen(path, "wb");
    if (!f) die("cannot create %s: %s", path, strerror(errno));
    if (size && fwrite(data, 1, size, f) != size) die("short write on %s", path);
    if (fclose(f) != 0) die("cannot close %s: %s", path, strerror(errno));
}

static void *load_sym(void *lib, const char *name, int required) {
    void *p = dlsym(lib, name);
    if (!p && required) die("dlsym(%s) failed: %s", name, dlerror());
    return p;
}

static atomic_int g_embree_error;
static void on_embree_error(void *user, int code, const char *str) {
    (void)user;
    fprintf(stderr, "embree_trace: Embree error %d: %s\n", code, str ? str : "(no message)");
    atomic_store(&g_embree_error, code ? code : 1);
}

static void check_device(RTCDevice dev, const char *what) {
    int code = rtc.GetDeviceError(dev);
    if (code == 0) code = atomic_load(&g_embree_error);
    if (code != 0) {
        const char *msg = rtc.GetDeviceLastErrorMessage ? rtc.GetDeviceLastErrorMessage(dev) : NULL;
        die("Embree device error %d after %s%s%s", code, what, msg && *msg ? ": " : "",
            msg ? msg : "");
    }
}

/* Builds (commits) a scene over `ntri` soup triangles; returns the commit wall time. */
static RTCScene build_scene(RTCDevice dev, const float *tris, size_t ntri, double *commit_ms) {
    RTCScene scene = rtc.NewScene(dev);
    if (!scene) check_device(dev, "rtcNewScene"), die("rtcNewScene returned NULL");
    if (g_quality != 1) rtc.SetSceneBuildQuality(scene, g_quality);
    if (ntri > 0) {
        if (ntri > 0x55555555u) die("too many triangles for 32-bit indices: %zu", ntri);
        RTCGeometry geom = rtc.NewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
        if (!geom) check_device(dev, "rtcNewGeometry"), die("rtcNewGeometry returned NULL");
        if (g_quality != 1) rtc.SetGeometryBuildQuality(geom, g_quality);
        float *vb = rtc.SetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                             3 * sizeof(float), 3 * ntri);
        unsigned *ib = rtc.SetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                3 * sizeof(unsigned), ntri);
        check_device(dev, "rtcSetNewGeometryBuffer");
        if (!vb || !ib) die("rtcSetNewGeometryBuffer returned NULL");
        memcpy(vb, tris, ntri * 9 * sizeof(float));
        for (size_t i = 0; i < 3 * ntri; i++) ib[i] = (unsigned)i;
        rtc.CommitGeometry(geom);
        rtc.AttachGeometry(scene, geom);
        rtc.ReleaseGeometry(geom);
        check_device(dev, "geometry setup");
    }
    double t0 = now_ms();
    rtc.CommitScene(scene);
    double t1 = now_ms();
    check_device(dev, "rtcCommitScene");
    *commit_ms = t1 - t0;
    return scene;
}

/* ---------------------------------------------------------------------------------------
 * Thread pool: the main thread plus T-1 workers; all meet at `start` and `end` barriers.
 * ------------------------------------------------------------------------------------- */
typedef struct {
    uint32_t prim;
    float t, u, v;
} HitRec;

#define CHUNK 1024

static struct {
    RTCScene scene;
    const float *rays;
    HitRec *out;
    size_t n;
    int occlusion;
    int quit;
    atomic_size_t next;
    pthread_barrier_t start, end;
} job;

/* Rays begin..stop (a chunk) in packets of W: fill the packet, call, read it back. */
#define DEFINE_TRACE_PACKETS(W)                                                             \
    static void trace_packets##W(size_t begin, size_t stop) {                                \
        const float qnan = NAN;                                                              \
        for (size_t p = begin; p < stop; p += W) {                                           \
            int valid[W];                                                                    \
            RTCRayHit##W rh;                                                                 \
            RTCRay##W *ray = &rh.ray;                                                        \
            for (int k = 0; k < W; k++) {                                                    \
                size_t i = p + (size_t)k < stop ? p + (size_t)k : stop - 1;                  \
                const float *r = job.rays + 8 * i;                                           \
                valid[k] = p + (size_t)k < stop ? -1 : 0;                                    \
                ray->org_x[k] = r[0], ray->org_y[k] = r[1], ray->org_z[k] = r[2];            \
                ray->dir_x[k] = r[3], ray->dir_y[k] = r[4], ray->dir_z[k] = r[5];            \
                ray->tnear[k] = r[6], ray->tfar[k] = r[7], ray->time[k] = 0.0f;              \
                ray->mask[k] = 0xFFFFFFFFu, ray->id[k] = (unsigned)i, ray->flags[k] = 0;     \
                rh.hit.geomID[k] = rh.hit.primID[k] = RTC_INVALID_GEOMETRY_ID;               \
                rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;                               \
            }                                                                                \
            if (job.occlusion) rtc.Occluded##W(valid, job.scene, ray, NULL);                 \
            else rtc.Intersect##W(valid, job.scene, &rh, NULL);                              \
            for (int k = 0; k < W && p + (size_t)k < stop; k++) {                            \
                HitRec h = {0xFFFFFFFFu, qnan, qnan, qnan};                                  \
                if (job.occlusion) {                                                         \
                    if (ray->tfar[k] < 0.0f) h.prim = 0;                                     \
                } else if (rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID) {                    \
                    h.prim = rh.hit.primID[k], h.t = ray->tfar[k];                           \
                    h.u = rh.hit.u[k], h.v = rh.hit.v[k];                                    \
                }                                                                            \
                job.out[p + (size_t)k] = h;                                                  \
            }                                                                                \
        }                                                                                    \
    }
DEFINE_TRACE_PACKETS(4)
DEFINE_TRACE_PACKETS(8)
DEFINE_TRACE_PACKETS(16)

static void trace_chunks(void) {
    const float qnan = NAN;
    const RTCScene scene = job.scene;
    const float *rays = job.rays;
    HitRec *out = job.out;
    const size_t n = job.n;
    for (;;) {
        size_t begin = atomic_fetch_add_explicit(&job.next, CHUNK, memory_order_relaxed);
        if (begin >= n) break;
        size_t stop = begin + CHUNK < n ? begin + CHUNK : n;
        if (g_packet == 16) trace_packets16(begin, stop);
        else if (g_packet == 8) trace_packets8(begin, stop);
        else if (g_packet == 4) trace_packets4(begin, stop);
        else if (!job.occlusion) {
            for (size_t i = begin; i < stop; i++) {
                const float *r = rays + 8 * i;
                RTCRayHit rh;
                rh.ray.org_x = r[0], rh.ray.org_y = r[1], rh.ray.org_z = r[2];
                rh.ray.dir_x = r[3], rh.ray.dir_y = r[4], rh.ray.dir_z = r[5];
                rh.ray.tnear = r[6], rh.ray.tfar = r[7];
                rh.ray.time = 0.0f;
                rh.ray.mask = 0xFFFFFFFFu, rh.ray.id = (unsigned)i, rh.ray.flags = 0;
                rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
                rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
                rtc.Intersect1(scene, &rh, NULL);
                HitRec h;
                if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
                    h.prim = rh.hit.primID, h.t = rh.ray.tfar, h.u = rh.hit.u, h.v = rh.hit.v;
                } else {
                    h.prim = 0xFFFFFFFFu, h.t = qnan, h.u = qnan, h.v = qnan;
                }
                out[i] = h;
            }
        } else {
            for (size_t i = begin; i < stop; i++) {
                const float *r = rays + 8 * i;
                RTCRay ray;
                ray.org_x = r[0], ray.org_y = r[1], ray.org_z = r[2];
                ray.dir_x = r[3], ray.dir_y = r[4], ray.dir_z = r[5];
                ray.tnear = r[6], ray.tfar = r[7];
                ray.time = 0.0f;
                ray.mask = 0xFFFFFFFFu, ray.id = (unsigned)i, ray.flags = 0;
                rtc.Occluded1(scene, &ray, NULL);
                HitRec h = {ray.tfar < 0.0f ? 0u : 0xFFFFFFFFu, qnan, qnan, qnan};
                out[i] = h;
            }
        }
    }
}

static void *worker_main(void *arg) {
    (void)arg;
    for (;;) {
        pthread_barrier_wait(&job.start);
        if (job.quit) break;
        trace_chunks();
        pthread_barrier_wait(&job.end);
    }
    return NULL;
}

/* One pass over the current job; returns its wall time (barrier release to last chunk). */
static double run_pass(void) {
    atomic_store(&job.next, 0);
    double t0 = now_ms();
    pthread_barrier_wait(&job.start);
    trace_chunks();
    pthread_barrier_wait(&job.end);
    return now_ms() - t0;
}

/* ------------------------------------------------------------------------------------- */

static void usage(FILE *f) {
    fputs("usage: embree_trace DIR --lib PATH [--threads T] [--passes P] [--no-write]\n"
          "                    [--sets primary,diffuse,shadow] [--build-threads N]\n"
          "                    [--name embree] [--device-config STR] [--quality Q]\n"
          "  --threads T        tracing threads (default 1)\n"
          "  --passes P         passes per set, the fastest counts (default 5)\n"
          "  --build-threads N  Embree device threads used by rtcCommitScene\n"
          "                     (default: T; 0 = Embree's default, all cores)\n"
          "  --quality Q        build quality: low, medium (Embree's default) or high\n"
          "                     (spatial splits)\n"
          "  --packet W         rays per call: 1 (rtcIntersect1, default), 4, 8 or 16\n"
          "                     (rtcIntersectW, as Mitsuba 3's LLVM variants call it)\n"
          "  --no-write         do not write DIR/<set>.<name>.hits\n",
          f);
}

static long parse_long(const char *opt, const char *s, long lo) {
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (errno || *end || end == s || v < lo) die("bad value for %s: '%s'", opt, s);
    return v;
}

int main(int argc, char **argv) {
    const char *dir = NULL, *lib = NULL, *sets_arg = "primary,diffuse,shadow";
    const char *name = "embree", *extra_cfg = NULL;
    long threads = 1, passes = 5, build_threads = -1;
    int write = 1;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
#define NEXT() (i + 1 < argc ? argv[++i] : (die("%s needs a value", a), (char *)NULL))
        if (!strcmp(a, "--lib")) lib = NEXT();
        else if (!strcmp(a, "--threads")) threads = parse_long(a, NEXT(), 1);
        else if (!strcmp(a, "--passes")) passes = parse_long(a, NEXT(), 1);
        else if (!strcmp(a, "--build-threads")) build_threads = parse_long(a, NEXT(), 0);
        else if (!strcmp(a, "--sets")) sets_arg = NEXT();
        else if (!strcmp(a, "--name")) name = NEXT();
        else if (!strcmp(a, "--device-config")) extra_cfg = NEXT();
        else if (!strcmp(a, "--no-write")) write = 0;
        else if (!strcmp(a, "--quality")) {
            const char *q = NEXT();
            if (!strcmp(q, "low")) g_quality = 0;
            else if (!strcmp(q, "medium")) g_quality = 1;
            else if (!strcmp(q, "high")) g_quality = 2;
            else die("bad value for --quality: '%s' (low, medium or high)", q);
        }
        else if (!strcmp(a, "--packet")) {
            g_packet = (int)parse_long(a, NEXT(), 1);
            if (g_packet != 1 && g_packet != 4 && g_packet != 8 && g_packet != 16)
                die("bad value for --packet: %d (1, 4, 8 or 16)", g_packet);
        }
        else if (!strcmp(a, "-h") || !strcmp(a, "--help")) { usage(stdout); return 0; }
        else if (a[0] == '-' && a[1] == '-') { usage(stderr); die("unknown option %s", a); }
        else if (!dir) dir = a;
        else { usage(stderr); die("unexpected argument %s", a); }
#undef NEXT
    }
    if (!dir || !lib) { usage(stderr); die("DIR and --lib PATH are required"); }
    if (build_threads < 0) build_threads = threads;

    /* ---- sets ---- */
    char sets[8][32];
    int nsets = 0;
    {
        char tmp[256];
        snprintf(tmp, sizeof tmp, "%s", sets_arg);
        for (char *tok = strtok(tmp, ","); tok; tok = strtok(NULL, ",")) {
            if (nsets == 8) die("too many sets");
            if (strlen(tok) >= sizeof sets[0]) die("set name too long: %s", tok);
            snprintf(sets[nsets++], sizeof sets[0], "%s", tok);
        }
        if (nsets == 0) die("--sets is empty");
    }

    /* ---- inputs (all read and checked before Embree is touched) ---- */
    char path[4096];
    size_t ntri;
    snprintf(path, sizeof path, "%s/triangles.f32", dir);
    float *tris = read_records(path, 36, &ntri);
    float *rays[8];
    size_t nrays[8];
    for (int s = 0; s < nsets; s++) {
        snprintf(path, sizeof path, "%s/%s.rays", dir, sets[s]);
        rays[s] = read_records(path, 32, &nrays[s]);
    }

    /* ---- Embree ---- */
    void *h = dlopen(lib, RTLD_NOW | RTLD_LOCAL);
    if (!h) die("dlopen(%s) failed: %s", lib, dlerror());
    rtc.NewDevice = load_sym(h, "rtcNewDevice", 1);
    rtc.ReleaseDevice = load_sym(h, "rtcReleaseDevice", 1);
    rtc.GetDeviceError = load_sym(h, "rtcGetDeviceError", 1);
    rtc.GetDeviceLastErrorMessage = load_sym(h, "rtcGetDeviceLastErrorMessage", 0);
    rtc.SetDeviceErrorFunction = load_sym(h, "rtcSetDeviceErrorFunction", 1);
    rtc.GetDeviceProperty = load_sym(h, "rtcGetDeviceProperty", 1);
    rtc.NewScene = load_sym(h, "rtcNewScene", 1);
    rtc.ReleaseScene = load_sym(h, "rtcReleaseScene", 1);
    rtc.CommitScene = load_sym(h, "rtcCommitScene", 1);
    rtc.NewGeometry = load_sym(h, "rtcNewGeometry", 1);
    rtc.ReleaseGeometry = load_sym(h, "rtcReleaseGeometry", 1);
    rtc.CommitGeometry = load_sym(h, "rtcCommitGeometry", 1);
    rtc.AttachGeometry = load_sym(h, "rtcAttachGeometry", 1);
    rtc.SetNewGeometryBuffer = load_sym(h, "rtcSetNewGeometryBuffer", 1);
    rtc.Intersect1 = load_sym(h, "rtcIntersect1", 1);
    rtc.Occluded1 = load_sym(h, "rtcOccluded1", 1);
    rtc.Intersect4 = load_sym(h, "rtcIntersect4", g_packet == 4);
    rtc.Occluded4 = load_sym(h, "rtcOccluded4", g_packet == 4);
    rtc.Intersect8 = load_sym(h, "rtcIntersect8", g_packet == 8);
    rtc.Occluded8 = load_sym(h, "rtcOccluded8", g_packet == 8);
    rtc.Intersect16 = load_sym(h, "rtcIntersect16", g_packet == 16);
    rtc.Occluded16 = load_sym(h, "rtcOccluded16", g_packet == 16);
    rtc.SetSceneBuildQuality = load_sym(h, "rtcSetSceneBuildQuality", 1);
    rtc.SetGeometryBuildQuality = load_sym(h, "rtcSetGeometryBuildQuality", 1);

    char cfg[512];
    if (build_threads > 0)
        snprintf(cfg, sizeof cfg, "threads=%ld%s%s", build_threads, extra_cfg ? "," : "",
                 extra_cfg ? extra_cfg : "");
    else
        snprintf(cfg, sizeof cfg, "%s", extra_cfg ? extra_cfg : "");
    RTCDevice dev = rtc.NewDevice(cfg);
    if (!dev) {
        int code = rtc.GetDeviceError(NULL);
        const char *msg = rtc.GetDeviceLastErrorMessage ? rtc.GetDeviceLastErrorMessage(NULL) : NULL;
        die("rtcNewDevice(\"%s\") failed: error %d%s%s", cfg, code, msg ? ": " : "", msg ? msg : "");
    }
    rtc.SetDeviceErrorFunction(dev, on_embree_error, NULL);
    check_device(dev, "rtcNewDevice");
    long version = (long)rtc.GetDeviceProperty(dev, RTC_DEVICE_PROPERTY_VERSION);
    long culling = (long)rtc.GetDeviceProperty(dev, RTC_DEVICE_PROPERTY_BACKFACE_CULLING_ENABLED);
    long tasking = (long)rtc.GetDeviceProperty(dev, RTC_DEVICE_PROPERTY_TASKING_SYSTEM);
    check_device(dev, "rtcGetDeviceProperty");
    if (culling) fprintf(stderr, "embree_trace: warning: this Embree build culls back faces\n");

    /* Warm-up commit (not timed): starts the tasking system's threads. */
    {
        enum { W = 16384 };
        float *wt = xmalloc((size_t)W * 36);
        uint32_t s = 12345u;
        for (size_t i = 0; i < (size_t)W * 9; i++) {
            s = s * 1664525u + 1013904223u;
            wt[i] = (float)(s >> 8) * (1.0f / 16777216.0f) + (float)((i / 9) % 64);
        }
        double ms;
        RTCScene ws = build_scene(dev, wt, W, &ms);
        rtc.ReleaseScene(ws);
        free(wt);
    }

    double build_ms;
    RTCScene scene = build_scene(dev, tris, ntri, &build_ms);

    /* ---- threads ---- */
    job.scene = scene;
    pthread_barrier_init(&job.start, NULL, (unsigned)threads);
    pthread_barrier_init(&job.end, NULL, (unsigned)threads);
    pthread_t *tids = calloc((size_t)threads, sizeof(pthread_t));
    for (long t = 1; t < threads; t++)
        if (pthread_create(&tids[t], NULL, worker_main, NULL) != 0) die("pthread_create failed");

    /* ---- sets ---- */
    double best_ms[8], median_ms[8];
    size_t hits[8];
    for (int s = 0; s < nsets; s++) {
        size_t n = nrays[s];
        HitRec *out = xmalloc(n * sizeof(HitRec));
        job.rays = rays[s];
        job.out = out;
        job.n = n;
        job.occlusion = strcmp(sets[s], "shadow") == 0;
        double *ms = calloc((size_t)passes, sizeof(double));
        for (long p = 0; p < passes; p++) ms[p] = run_pass();
        check_device(dev, sets[s]);
        best_ms[s] = ms[0];
        for (long p = 1; p < passes; p++)
            if (ms[p] < best_ms[s]) best_ms[s] = ms[p];
        /* median (insertion sort, P is small) */
        for (long a = 1; a < passes; a++)
            for (long b = a; b > 0 && ms[b] < ms[b - 1]; b--) {
                double x = ms[b]; ms[b] = ms[b - 1]; ms[b - 1] = x;
            }
        median_ms[s] = passes % 2 ? ms[passes / 2] : 0.5 * (ms[passes / 2 - 1] + ms[passes / 2]);
        free(ms);
        hits[s] = 0;
        for (size_t i = 0; i < n; i++) hits[s] += out[i].prim != 0xFFFFFFFFu;
        if (write) {
            snprintf(path, sizeof path, "%s/%s.%s.hits", dir, sets[s], name);
            write_file(path, out, n * sizeof(HitRec));
        }
        free(out);
    }

    job.quit = 1;
    pthread_barrier_wait(&job.start);
    for (long t = 1; t < threads; t++) pthread_join(tids[t], NULL);
    free(tids);

    rtc.ReleaseScene(scene);
    check_device(dev, "rtcReleaseScene");
    rtc.ReleaseDevice(dev);

    /* ---- report ---- */
    printf("{\"tracer\": \"%s\", \"threads\": %ld, \"triangles\": %zu, \"build_ms\": %.4f, "
           "\"build\": \"default\", \"build_threads\": %ld, \"passes\": %ld, \"packet\": %d, "
           "\"embree_version\": \"%ld.%ld.%ld\", \"tasking_system\": %ld, \"sets\": {",
           name, threads, ntri, build_ms, build_threads, passes, g_packet, version / 10000,
           version / 100 % 100, version % 100, tasking);
    for (int s = 0; s < nsets; s++) {
        double mrays = best_ms[s] > 0 ? (double)nrays[s] / (best_ms[s] * 1e3) : 0.0;
        printf("%s\"%s\": {\"rays\": %zu, \"mrays_per_s\": %.4f, \"hits\": %zu, "
               "\"best_ms\": %.6f, \"median_ms\": %.6f}",
               s ? ", " : "", sets[s], nrays[s], mrays, hits[s], best_ms[s], median_ms[s]);
    }
    printf("}}\n");
    fflush(stdout);
    for (int s = 0; s < nsets; s++) free(rays[s]);
    free(tris);
    return 0;
}
