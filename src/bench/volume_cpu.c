/* Pictures with the diffuse light volume, drawn on the CPU (experiments.h,
 * bench_volume_image): how the bench measures the 3-D diffuse light against Monte Carlo before
 * the eye pass reads it. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bench/bench.h"
#include "bench/experiments.h"
#include "bench/scenes.h"
#include "config/config.h"
#include "common/log.h"
#include "common/mat4d.h"
#include "light/light.h"
#include "light/light_volume.h"
#include "render/image.h"

#define PI 3.14159265358979323846
#define PHASE_TABLE 1024

/* clip -> world (row-major) of the column-major VIEW and PROJ; false when singular. */
static bool clip_to_world(const struct render_view *v, double out[16])
{
    double m[16];
    for (int i = 0; i < 4; i++) {
        for (int j = 0; j < 4; j++) {
            double s = 0.0;
            for (int k = 0; k < 4; k++)
                s += (double)v->proj[4 * k + i] * v->view[4 * j + k];
            m[4 * i + j] = s;
        }
    }
    return mat4d_invert(m, out);
}

static void unproject(const double inv[16], double x, double y, double z, double out[3])
{
    double v[4] = {x, y, z, 1.0}, r[4];
    for (int i = 0; i < 4; i++)
        r[i] = inv[4 * i] * v[0] + inv[4 * i + 1] * v[1] + inv[4 * i + 2] * v[2] + inv[4 * i + 3];
    for (int i = 0; i < 3; i++)
        out[i] = r[i] / r[3];
}

static double beam_at(const struct light_map *map, const double p[3])
{
    double t[3];
    light_grid_world_to_tex(&map->grid, p, t);
    if (!(t[0] >= 0.0 && t[0] <= 1.0 && t[1] >= 0.0 && t[1] <= 1.0))
        return 1.0;
    float tf[3] = {(float)t[0], (float)t[1], (float)t[2]};
    return light_map_sample(map, tf);
}

/* The eye phase table's value at the scattering angle whose cosine is MU, for phase P (0 ice,
 * 1 water), linear between entries. */
static double eye_phase(const float *table, double mu, int p)
{
    double a = acos(fmax(-1.0, fmin(1.0, mu))) / PI * (PHASE_TABLE - 1);
    int i = (int)a;
    if (i >= PHASE_TABLE - 1)
        return table[2 * (PHASE_TABLE - 1) + p];
    double t = a - i;
    return table[2 * i + p] + t * (table[2 * (i + 1) + p] - table[2 * i + p]);
}

/* Radiance along the ray O + t DIR (unit) through the box [LO, HI]. */
static double march(const struct bench_scene *sc, const struct light_map *map,
                    const struct light_volume *lv, const float *table, const double g[2],
                    const double lo[3], const double hi[3], double smax, const double o[3],
                    const double dir[3])
{
    double t0 = 0.0, t1 = INFINITY;
    for (int a = 0; a < 3; a++) {
        if (fabs(dir[a]) < 1e-300) {
            if (o[a] < lo[a] || o[a] > hi[a])
                return 0.0;
            continue;
        }
        double ta = (lo[a] - o[a]) / dir[a], tb = (hi[a] - o[a]) / dir[a];
        if (ta > tb) {
            double x = ta;
            ta = tb;
            tb = x;
        }
        t0 = fmax(t0, ta);
        t1 = fmin(t1, tb);
    }
    if (!(t1 > t0))
        return 0.0;
    double len = sqrt(sc->sun[0] * sc->sun[0] + sc->sun[1] * sc->sun[1] + sc->sun[2] * sc->sun[2]);
    /* cosine of the scattering angle: sunlight along -sun, scattered along -dir to the eye */
    double mu = (sc->sun[0] * dir[0] + sc->sun[1] * dir[1] + sc->sun[2] * dir[2]) / len;
    double pv_ice = eye_phase(table, mu, 0), pv_water = eye_phase(table, mu, 1);
    const double to_eye[3] = {-dir[0], -dir[1], -dir[2]};
    double radiance = 0.0, trans = 1.0, t = t0;
    while (t < t1 && trans > 1e-6) {
        double p[3];
        for (int a = 0; a < 3; a++)
            p[a] = o[a] + t * dir[a];
        float pf[3] = {(float)p[0], (float)p[1], (float)p[2]}, b[2];
        light_sample_beta(sc->vol, pf, b);
        double beta = (double)b[0] + b[1];
        double ds = fmin(smax, t1 - t);
        if (beta > 0.0)
            ds = fmin(ds, 0.05 / beta);
        for (int a = 0; a < 3; a++)
            p[a] = o[a] + (t + 0.5 * ds) * dir[a];
        pf[0] = (float)p[0];
        pf[1] = (float)p[1];
        pf[2] = (float)p[2];
        light_sample_beta(sc->vol, pf, b);
        beta = (double)b[0] + b[1];
        if (beta > 0.0) {
            double ts = exp(-beta * ds);
            double pv = (b[0] * pv_ice + b[1] * pv_water) / beta;
            double gm = (b[0] * g[1] + b[1] * g[0]) / beta;
            float f[4];
            light_volume_sample(lv, p, f);
            double diffuse = light_volume_scattered(f, (float)gm, to_eye);
            radiance += trans * (1.0 - ts) * (pv * beam_at(map, p) + diffuse);
            trans *= ts;
        }
        t += ds;
    }
    return radiance;
}

bool bench_volume_image(const struct bench_scene *sc, struct image *out,
                        struct bench_volume_timing *timing)
{
    memset(out, 0, sizeof(*out));
    struct light_map map = {0};
    struct light_volume lv = {0};
    float *table = malloc(2 * PHASE_TABLE * sizeof(float));
    double inv[16];
    bool ok = false;
    if (!table || !clip_to_world(&sc->view, inv)) {
        log_error("bench: no memory for the phase table, or singular camera matrices");
        goto done;
    }
    optics_eye_phase_table(&sc->optics, PHASE_TABLE, table);
    double t_start = time_now_ms();
    if (!light_map_build(sc->vol, sc->sun, &sc->light, &map))
        goto done;
    double t_map = time_now_ms();
    if (!light_volume_build(sc->vol, &map, &sc->light, NULL, &lv))
        goto done;
    double t_vol = time_now_ms();
    if (timing) {
        timing->map_ms += t_map - t_start;
        timing->volume_ms += t_vol - t_map;
        timing->builds++;
        timing->iterations += lv.iterations;
    }
    log_info("bench: diffuse light volume %dx%dx%d, %d iterations (residual %.2g), source %.4g, "
             "leak %.4g, light map %.0f ms, volume %.0f ms", lv.grid.n[0], lv.grid.n[1],
             lv.grid.n[2], lv.iterations, lv.residual, lv.source, lv.leak, t_map - t_start,
             t_vol - t_map);

    const struct grid3 *gr = &sc->vol->grid;
    double lo[3], hi[3], smax = INFINITY;
    for (int a = 0; a < 3; a++) {
        lo[a] = gr->origin[a];
        hi[a] = gr->origin[a] + gr->n[a] * gr->spacing[a];
        smax = fmin(smax, 0.25 * gr->spacing[a]);
    }
    /* mean cosines [0] water, [1] ice: 1 - 4 gamma / 3 */
    const double g[2] = {1.0 - 4.0 * sc->light.cp.water_gamma / 3.0,
                         1.0 - 4.0 * sc->light.cp.ice_gamma / 3.0};
    const int w = sc->view.width, h = sc->view.height;
    if (!image_init(out, w, h))
        goto done;
    for (int y = 0; y < h; y++) {
        for (int x = 0; x < w; x++) {
            double nx = (x + 0.5) / w * 2.0 - 1.0, ny = (y + 0.5) / h * 2.0 - 1.0;
            double o[3], f[3], d[3];
            unproject(inv, nx, ny, -1.0, o);
            unproject(inv, nx, ny, 1.0, f);
            double n = 0.0;
            for (int a = 0; a < 3; a++) {
                d[a] = f[a] - o[a];
                n += d[a] * d[a];
            }
            n = sqrt(n);
            for (int a = 0; a < 3; a++)
                d[a] /= n;
            double l = march(sc, &map, &lv, table, g, lo, hi, smax, o, d);
            float *px = out->rgba + 4 * ((size_t)y * w + x);
            for (int c = 0; c < 3; c++)
                px[c] = (float)(l * sc->settings.sun_radiance[c]);
            px[3] = 1.0f;
        }
    }
    ok = true;
done:
    free(table);
    light_map_finish(&map);
    light_volume_finish(&lv);
    if (!ok)
        image_finish(out);
    return ok;
}

bool bench_volume_time_storm(const char *configs, bool quick, struct bench_volume_timing *out,
                             int cells[3])
{
    memset(out, 0, sizeof(*out));
    struct config cfg;
    if (!bench_scene_config("storm", configs, quick, NULL, 0, &cfg))
        return false;
    struct ext_volume vol = {0};
    struct bench_scene sc;
    struct light_map map = {0};
    struct light_volume lv = {0};
    bool ok = false;
    if (!bench_scene_prepare("storm", &cfg, 64, 48, &vol, &sc))
        goto done;
    double t0 = time_now_ms();
    if (!light_map_build(sc.vol, sc.sun, &sc.light, &map))
        goto done;
    double t1 = time_now_ms();
    if (!light_volume_build(sc.vol, &map, &sc.light, NULL, &lv))
        goto done;
    double t2 = time_now_ms();
    out->map_ms = t1 - t0;
    out->volume_ms = t2 - t1;
    out->builds = 1;
    out->iterations = lv.iterations;
    for (int a = 0; a < 3; a++)
        cells[a] = lv.grid.n[a];
    ok = true;
done:
    light_map_finish(&map);
    light_volume_finish(&lv);
    ext_volume_finish(&vol);
    return ok;
}
