/* The probe in a session (docs/analysis.md): the point a scripted pointer picks on the first
 * visible cloud travels in the frame state alone, and a second session without a menu, fed
 * those frame states as bytes, reads the same values from its own data and draws the same
 * pictures, panel and cross included; the point lies on the ray where the extinction reaches
 * the threshold; the light map's value at a point, read back from the GPU, is the value of
 * the whole map read back (dense) or of the compressed columns (compressed). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "testutil.h"

#include "common/log.h"
#include "data/probe.h"
#include "display/display.h"
#include "gpu/gpu.h"
#include "light/light.h"
#include "light/light_gpu.h"
#include "render/image.h"
#include "session/frame.h"
#include "session/scene.h"
#include "session/session.h"

static struct gpu_context *ctx;

static struct display *open_display(const struct config *cfg, struct display_config *dcfg)
{
    display_config_defaults(dcfg);
    dcfg->type = DISPLAY_TYPE_ORBIT;
    dcfg->window_size[0] = cfg->render.width;
    dcfg->window_size[1] = cfg->render.height;
    struct display_desc dd = {.offscreen = true, .context = ctx, .height = cfg->render.height};
    scene_camera(cfg, &dd.camera);
    struct display *d = display_create(dcfg, &dd);
    assert_non_null(d);
    assert_true(display_update(d, 0.0));
    return d;
}

static struct session *make(const struct config *cfg, const struct display_config *dcfg,
                            const char *script)
{
    int rc;
    struct session *s = session_create(cfg,
                                       &(struct session_desc){
                                           .command = "render",
                                           .display = dcfg,
                                           .views_move = true,
                                           .playback = true,
                                           .menu = script != NULL,
                                           .script = script,
                                           .probe = true,
                                       },
                                       &rc);
    assert_non_null(s);
    return s;
}

/* The world ray through pixel (PX, PY) (row 0 at the top) of CFG's camera. */
static void pixel_ray(const struct config *cfg, double px, double py, double o[3], double d[3])
{
    double f[3], r[3], u[3], len = 0.0;
    for (int i = 0; i < 3; i++) {
        o[i] = cfg->camera.position_km[i] * 1000.0;
        f[i] = (cfg->camera.target_km[i] - cfg->camera.position_km[i]) * 1000.0;
        len += f[i] * f[i];
    }
    for (int i = 0; i < 3; i++)
        f[i] /= sqrt(len);
    const double *up = cfg->camera.up;
    r[0] = f[1] * up[2] - f[2] * up[1];
    r[1] = f[2] * up[0] - f[0] * up[2];
    r[2] = f[0] * up[1] - f[1] * up[0];
    len = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    for (int i = 0; i < 3; i++)
        r[i] /= len;
    u[0] = r[1] * f[2] - r[2] * f[1];
    u[1] = r[2] * f[0] - r[0] * f[2];
    u[2] = r[0] * f[1] - r[1] * f[0];
    double w = cfg->render.width, h = cfg->render.height;
    double x = (px + 0.5) / w * 2.0 - 1.0, y = 1.0 - (py + 0.5) / h * 2.0;
    double t = tan(cfg->camera.fov_deg * M_PI / 360.0);
    len = 0.0;
    for (int i = 0; i < 3; i++) {
        d[i] = f[i] + x * t * w / h * r[i] + y * t * u[i];
        len += d[i] * d[i];
    }
    for (int i = 0; i < 3; i++)
        d[i] /= sqrt(len);
}

static void test_point_travels_in_the_frame_state(void **state)
{
    if (access(test_shared_data("wrf/katrina_2005_mercator_wsm3.nc"), R_OK) != 0)
        skip();
    struct config cfg;
    /* A camera of its own (the one pixel_ray follows; not the framing of the data). */
    test_config_file(&cfg, ANVIL_SOURCE_DIR "/configs/katrina.cfg",
                     (const char *[]){"render.width=160", "render.height=120",
                                      "lightmap.resolution=[32,32,32]", "probe.on=true",
                                      "camera.position=[-60,-120,90]",
                                      "camera.target=[240,240,0]", "camera.fov=45",
                                      "camera.far=5000"},
                     8);
    /* The pointer on the cloud in the middle of Katrina's picture (docs/analysis.md). */
    double o[3], d[3];
    pixel_ray(&cfg, 90.0, 75.0, o, d);
    char script[512];
    snprintf(script, sizeof(script), "0 pose world %.3f %.3f %.3f %.6f %.6f %.6f\n", o[0], o[1],
             o[2], d[0], d[1], d[2]);
    const char *path = test_write_file("probe.txt", script);
    struct display_config dca, dcb;
    struct display *da = open_display(&cfg, &dca), *db = open_display(&cfg, &dcb);
    struct session *a = make(&cfg, &dca, path), *b = make(&cfg, &dcb, NULL);
    bool seen = false;
    for (int frame = 0; frame < 4; frame++) {
        struct frame_state fa, fb;
        bool redraw;
        assert_true(session_update(a, NULL, session_script_dt(a), 0.0, &fa, &redraw));
        uint8_t bytes[FRAME_STATE_BYTES];
        frame_state_write(&fa, bytes);
        assert_true(frame_state_read(bytes, sizeof(bytes), &fb));
        assert_true(session_apply(a, &fa, NULL) && session_light(a) &&
                    display_sample_head(da, 0.0, &fa.head) && session_draw(a, da, &fa));
        fb.head = fa.head;
        assert_true(session_apply(b, &fb, NULL) && session_light(b) && session_draw(b, db, &fb));
        struct image ia, ib;
        assert_true(renderer_read(&display_view(da, 0)->target, &ia));
        assert_true(renderer_read(&display_view(db, 0)->target, &ib));
        size_t n = sizeof(float) * 4 * (size_t)ia.width * (size_t)ia.height;
        if (memcmp(ia.rgba, ib.rgba, n) != 0)
            fail_msg("frame %d: the session fed the frame states drew another picture", frame);
        image_finish(&ia);
        image_finish(&ib);
        const struct probe_values *va = session_probe(a), *vb = session_probe(b);
        assert_non_null(va);
        assert_non_null(vb);
        assert_int_equal(va->valid, vb->valid);
        if (!fa.probe_valid)
            continue;
        seen = true;
        assert_true(va->valid);
        /* Each read its own data: the same numbers. */
        assert_memory_equal(&va->s, &vb->s, sizeof(va->s));
        assert_memory_equal(va->beta, vb->beta, sizeof(va->beta));
        assert_true(va->have_light && vb->have_light && va->light == vb->light);
        /* On the ray, where the extinction reaches the threshold. */
        double along = 0.0, off = 0.0;
        for (int i = 0; i < 3; i++)
            along += (fa.probe_point[i] - o[i]) * d[i];
        for (int i = 0; i < 3; i++) {
            double e = fa.probe_point[i] - o[i] - along * d[i];
            off += e * e;
        }
        assert_true(along > 0.0 && sqrt(off) < 1.0);
        double beta = va->beta[0] + va->beta[1];
        assert_true(fabs(beta - cfg.probe.threshold) < 0.01 * cfg.probe.threshold);
        /* A cloud: condensate in the data there, and light within [0, 1]. */
        assert_true(va->fields && probe_sample_condensate(&va->s) > 0.0);
        assert_true(va->light >= 0.0 && va->light <= 1.0);
    }
    assert_true(seen);
    /* The same last frame in a session whose probe is off: the panel and the cross were part
     * of the picture. */
    struct config off = cfg;
    off.probe.on = false;
    struct display_config dcc;
    struct display *dc = open_display(&off, &dcc);
    struct session *c = make(&off, &dcc, NULL);
    struct frame_state fa;
    bool redraw;
    assert_true(session_update(a, NULL, session_script_dt(a), 0.0, &fa, &redraw));
    assert_true(fa.probe_valid);
    assert_true(session_apply(a, &fa, NULL) && session_light(a) && session_draw(a, da, &fa));
    assert_true(session_apply(c, &fa, NULL) && session_light(c) && session_draw(c, dc, &fa));
    struct image ia, ic;
    assert_true(renderer_read(&display_view(da, 0)->target, &ia));
    assert_true(renderer_read(&display_view(dc, 0)->target, &ic));
    int differ = 0;
    for (size_t i = 0; i < 4 * (size_t)ia.width * (size_t)ia.height; i++)
        differ += ia.rgba[i] != ic.rgba[i];
    assert_true(differ > 1000);
    image_finish(&ia);
    image_finish(&ic);
    session_destroy(c);
    display_destroy(dc);
    session_destroy(a);
    session_destroy(b);
    display_destroy(da);
    display_destroy(db);
}

/* The light map's value at points, read back around each: the value of the whole map read
 * back; in compressed mode that of the columns the compressor made from that map. */
static void test_light_at_a_point(void **state)
{
    struct config cfg;
    test_config_from(&cfg,
                     (const char *[]){"scene.size=[32,32,16]", "lightmap.resolution=[24,24,32]",
                                      "light.elevation=30"},
                     3);
    struct renderer *r = renderer_create();
    assert_non_null(r);
    struct ext_volume vol = {0};
    test_upload_scene(r, &cfg, &vol);
    struct light_settings s;
    light_settings_defaults(&s);
    memcpy(s.resolution, cfg.lightmap.resolution, sizeof(s.resolution));
    s.multiple = true;
    s.epsilon = 0.01;
    light_settings_set_optics(&s, &cfg.optics.params, cfg.lightmap.forward_angle_deg);
    double sun[3];
    light_sun_direction(cfg.light.azimuth_deg, cfg.light.elevation_deg, sun);
    struct light_gpu *lg = light_gpu_create();
    assert_non_null(lg);
    struct light_gpu_source src = {renderer_volume_texture(r), renderer_grid(r), 1, 1, NULL};
    float beam, diffuse[2];
    bool have_diffuse;
    assert_false(light_gpu_sample(lg, (const double[3]){0, 0, 0}, &beam, diffuse,
                                  &have_diffuse)); /* nothing built yet */
    assert_true(light_gpu_update(lg, &src, sun, &s, LIGHT_GPU_DENSE, NULL));
    struct light_map map = {0};
    assert_true(light_gpu_read(lg, &map));
    const struct grid3 *g = &vol.grid;
    unsigned seed = 3;
    double lowest = 1.0;
    for (int i = 0; i < 200; i++) {
        double p[3], td[3];
        for (int a = 0; a < 3; a++) {
            seed = seed * 1103515245u + 12345u;
            p[a] = g->origin[a] + g->n[a] * g->spacing[a] * ((seed >> 8) & 0xffff) / 65536.0;
        }
        assert_true(light_gpu_sample(lg, p, &beam, diffuse, &have_diffuse));
        light_grid_world_to_tex(&map.grid, p, td);
        const float tex[3] = {(float)td[0], (float)td[1], (float)td[2]};
        assert_true(beam == light_map_sample(&map, tex));
        float md[2];
        light_map_sample_diffuse(&map, tex, md);
        assert_true(have_diffuse && diffuse[0] == md[0] && diffuse[1] == md[1]);
        lowest = fmin(lowest, beam);
    }
    assert_true(lowest < 0.5); /* points in the storm's shadow: not a map of ones */
    /* Compressed: the columns made from that very map. */
    struct light_compressed c;
    assert_true(light_compressed_build(&map, s.epsilon, &c));
    assert_true(light_gpu_update(lg, &src, sun, &s, LIGHT_GPU_COMPRESSED, NULL));
    for (int i = 0; i < 100; i++) {
        double p[3], td[3];
        for (int a = 0; a < 3; a++) {
            seed = seed * 1103515245u + 12345u;
            p[a] = g->origin[a] + g->n[a] * g->spacing[a] * ((seed >> 8) & 0xffff) / 65536.0;
        }
        assert_true(light_gpu_sample(lg, p, &beam, diffuse, &have_diffuse));
        light_grid_world_to_tex(&c.grid, p, td);
        const float tex[3] = {(float)td[0], (float)td[1], (float)td[2]};
        assert_true(beam == light_compressed_sample(&c, tex));
    }
    light_compressed_finish(&c);
    light_map_finish(&map);
    light_gpu_destroy(lg);
    ext_volume_finish(&vol);
    renderer_destroy(r);
}

int main(void)
{
    log_set_level(LOG_WARN);
    ctx = test_gl_context_or_skip();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_point_travels_in_the_frame_state),
        cmocka_unit_test(test_light_at_a_point),
    };
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    gpu_context_destroy(ctx);
    return rc;
}
