/* The frame state as bytes: explicit little-endian fields, so both ends agree on every
 * platform, and checks on the way in (network input is bad input too). */
#include "session/frame.h"

#include <math.h>
#include <string.h>

#include "common/log.h"

#define MAGIC 0x464e5641u /* "AVNF" */
#define VERSION 2u

struct writer {
    uint8_t *p;
    size_t n;
};

static void put_u64(struct writer *w, uint64_t v)
{
    for (int i = 0; i < 8; i++)
        w->p[w->n++] = (uint8_t)(v >> (8 * i));
}

static void put_u32(struct writer *w, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        w->p[w->n++] = (uint8_t)(v >> (8 * i));
}

static void put_f64(struct writer *w, double v)
{
    uint64_t u;
    memcpy(&u, &v, sizeof(u));
    put_u64(w, u);
}

static void put_f32(struct writer *w, float v)
{
    uint32_t u;
    memcpy(&u, &v, sizeof(u));
    put_u32(w, u);
}

static void put_f64s(struct writer *w, const double *v, int n)
{
    for (int i = 0; i < n; i++)
        put_f64(w, v[i]);
}

static void put_f32s(struct writer *w, const float *v, int n)
{
    for (int i = 0; i < n; i++)
        put_f32(w, v[i]);
}

struct reader {
    const uint8_t *p;
    size_t n;
    bool finite;
};

static uint64_t get_u64(struct reader *r)
{
    uint64_t v = 0;
    for (int i = 0; i < 8; i++)
        v |= (uint64_t)r->p[r->n++] << (8 * i);
    return v;
}

static uint32_t get_u32(struct reader *r)
{
    uint32_t v = 0;
    for (int i = 0; i < 4; i++)
        v |= (uint32_t)r->p[r->n++] << (8 * i);
    return v;
}

static double get_f64(struct reader *r)
{
    uint64_t u = get_u64(r);
    double v;
    memcpy(&v, &u, sizeof(v));
    r->finite = r->finite && isfinite(v);
    return v;
}

static float get_f32(struct reader *r)
{
    uint32_t u = get_u32(r);
    float v;
    memcpy(&v, &u, sizeof(v));
    r->finite = r->finite && isfinite(v);
    return v;
}

static void get_f64s(struct reader *r, double *v, int n)
{
    for (int i = 0; i < n; i++)
        v[i] = get_f64(r);
}

static void get_f32s(struct reader *r, float *v, int n)
{
    for (int i = 0; i < n; i++)
        v[i] = get_f32(r);
}

/* The fields in order; both directions go through this list. */
#define FIELDS(U64, U32, F64, F32, F64S, F32S)                                                   \
    U64(frame);                                                                                \
    F64(time_s);                                                                               \
    F64(dt_s);                                                                                 \
    F32S(head.position, 3);                                                                    \
    F32S(head.rotation, 4);                                                                    \
    F64(nav.scale);                                                                            \
    F64S(nav.origin_km, 3);                                                                    \
    F64S(nav.position, 3);                                                                     \
    F64S(nav.orientation_deg, 3);                                                              \
    F64S(camera.eye, 3);                                                                       \
    F64S(camera.target, 3);                                                                    \
    F64S(camera.up, 3);                                                                        \
    F64(camera.fov_deg);                                                                       \
    F64(camera.near_m);                                                                        \
    F64(camera.far_m);                                                                         \
    F32S(wand_position, 3);                                                                    \
    F32S(wand_direction, 3);                                                                   \
    F32(step_fraction);                                                                        \
    F64(sun_azimuth_deg);                                                                      \
    F64(sun_elevation_deg);                                                                    \
    U32(settings_revision);                                                                    \
    F64S(probe_point, 3)

size_t frame_state_write(const struct frame_state *f, uint8_t buf[FRAME_STATE_BYTES])
{
    memset(buf, 0, FRAME_STATE_BYTES);
    struct writer w = {buf, 0};
    put_u32(&w, MAGIC);
    put_u32(&w, VERSION);
    put_u32(&w, (uint32_t)f->time_step);
    put_u32(&w, (f->wand_valid ? 1u : 0u) | (f->playing ? 2u : 0u) | (f->menu_visible ? 4u : 0u) |
                    (f->probe_valid ? 8u : 0u));
#define W_U64(m) put_u64(&w, f->m)
#define W_U32(m) put_u32(&w, f->m)
#define W_F64(m) put_f64(&w, f->m)
#define W_F32(m) put_f32(&w, f->m)
#define W_F64S(m, n) put_f64s(&w, f->m, n)
#define W_F32S(m, n) put_f32s(&w, f->m, n)
    FIELDS(W_U64, W_U32, W_F64, W_F32, W_F64S, W_F32S);
    return FRAME_STATE_BYTES;
}

bool frame_state_read(const uint8_t *buf, size_t len, struct frame_state *out)
{
    if (len != FRAME_STATE_BYTES) {
        log_error("frame state: expected %d bytes, got %zu", FRAME_STATE_BYTES, len);
        return false;
    }
    struct reader r = {buf, 0, true};
    uint32_t magic = get_u32(&r), version = get_u32(&r);
    if (magic != MAGIC || version != VERSION) {
        log_error("frame state: expected magic %08x version %u, got %08x version %u", MAGIC,
                  VERSION, magic, version);
        return false;
    }
    struct frame_state f;
    memset(&f, 0, sizeof(f));
    f.time_step = (int32_t)get_u32(&r);
    uint32_t flags = get_u32(&r);
    if (flags & ~15u) {
        log_error("frame state: unknown flags %08x", flags);
        return false;
    }
    f.wand_valid = flags & 1u;
    f.playing = flags & 2u;
    f.menu_visible = flags & 4u;
    f.probe_valid = flags & 8u;
#define R_U64(m) f.m = get_u64(&r)
#define R_U32(m) f.m = get_u32(&r)
#define R_F64(m) f.m = get_f64(&r)
#define R_F32(m) f.m = get_f32(&r)
#define R_F64S(m, n) get_f64s(&r, f.m, n)
#define R_F32S(m, n) get_f32s(&r, f.m, n)
    FIELDS(R_U64, R_U32, R_F64, R_F32, R_F64S, R_F32S);
    for (size_t i = r.n; i < len; i++) {
        if (buf[i] != 0) {
            log_error("frame state: byte %zu past the fields is not zero", i);
            return false;
        }
    }
    if (!r.finite) {
        log_error("frame state: a number is not finite");
        return false;
    }
    double q = 0.0;
    for (int i = 0; i < 4; i++)
        q += (double)f.head.rotation[i] * f.head.rotation[i];
    if (fabs(q - 1.0) > 1e-3) {
        log_error("frame state: the head's rotation is not a unit quaternion (|q|^2 = %g)", q);
        return false;
    }
    if (!(f.step_fraction >= 0.0f && f.step_fraction <= 1.0f) || f.time_step < 0 ||
        !(f.nav.scale > 0.0) || !(f.dt_s >= 0.0)) {
        log_error("frame state: time step %d, fraction %g, scale %g or dt %g out of range",
                  (int)f.time_step, f.step_fraction, f.nav.scale, f.dt_s);
        return false;
    }
    *out = f;
    return true;
}
