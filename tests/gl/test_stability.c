/* Hard cases of SPEC.md ("Hard cases that must stay numerically stable") in the GPU light map
 * and the eye pass: optically very thick media, an empty volume, a single voxel, suns along
 * an axis and at grazing angles, cameras on a face, an edge, a corner, across the near plane
 * and inside, |g| -> 1, fp16 storage, bad extinction values and 1000:1 volumes.
 * docs/stability.md lists each case with its tests. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#include "session/lightmaps.h"
#include "session/scene.h"
#include "session/stats.h"
#include "common/log.h"
#include "gpu/gpu.h"
#include "light/light.h"
#include "light/light_gpu.h"
#include "render/camera.h"
#include "render/render.h"

static struct gpu_context *ctx;
static struct renderer *renderer;

/* Draws VIEW (the config's camera when NULL) with the light map the config asks for (every
 * auto effect on); LIGHT false draws without a light map. */
static void draw(const struct config *cfg, const struct render_view *view, bool light,
                 struct image *img)
{
    struct render_settings rs;
    scene_render_settings(cfg, &rs);
    struct render_view v;
    if (view)
        v = *view;
    else
        scene_camera_view(cfg, cfg->render.width, cfg->render.height, &v);
    struct lightmaps al;
    assert_true(lightmaps_init(&al, cfg));
    if (light)
        assert_true(lightmaps_update(&al, cfg, renderer, NULL));
    else
        renderer_set_light(renderer, NULL);
    struct gpu_texture out = {0};
    assert_true(renderer_draw(renderer, &rs, &v, &out));
    assert_true(renderer_read(&out, img));
    gpu_texture_finish(&out);
    renderer_set_light(renderer, NULL);
    lightmaps_finish(&al);
}

/* Largest eye phase P_v over the table: single scattering sum T (1 - T_s) P_v L_l L_sun can
 * never exceed it times L_sun (sum T (1 - T_s) <= 1, L_l <= 1). */
static float phase_max(const struct optics_params *optics)
{
    float table[2 * 512];
    optics_eye_phase_table(optics, 512, table);
    float m = 0.0f;
    for (int i = 0; i < 2 * 512; i++) {
        assert_true(isfinite(table[i]) && table[i] >= 0.0f);
        m = fmaxf(m, table[i]);
    }
    return m;
}

/* Every pixel finite, transmittance in [0, 1], radiance in [0, bound]. */
static void assert_bounded(const struct image *img, double bound)
{
    for (int i = 0; i < img->width * img->height; i++) {
        for (int c = 0; c < 3; c++) {
            float v = img->rgba[4 * i + c];
            assert_true(isfinite(v));
            assert_true(v >= 0.0f && v <= bound);
        }
        float a = img->rgba[4 * i + 3];
        assert_true(isfinite(a) && a >= 0.0f && a <= 1.0f);
    }
}

/* The GPU light map of the config's volume (already uploaded) for its sun, with the diffuse
 * volume of multiple scattering when MULTIPLE (PERIPHERAL: the peripheral ring, with FORWARD):
 * every node finite in [0, 1]; returned in MAP (finish it). */
static void gpu_light_map_with(const struct config *cfg, bool forward, bool peripheral,
                               bool multiple, struct light_map *map)
{
    struct light_settings s;
    light_settings_defaults(&s);
    memcpy(s.resolution, cfg->lightmap.resolution, sizeof(s.resolution));
    s.forward = forward;
    s.peripheral = peripheral;
    s.multiple = multiple;
    light_settings_set_optics(&s, &cfg->optics.params, cfg->lightmap.forward_angle_deg);
    double sun[3];
    light_sun_direction(cfg->light.azimuth_deg, cfg->light.elevation_deg, sun);
    struct light_gpu *lg = light_gpu_create();
    assert_non_null(lg);
    /* With the volume's macro cells: samples in empty cells read no voxel. */
    struct light_gpu_source src = {renderer_volume_texture(renderer), renderer_grid(renderer), 1,
                                   1, renderer_cells(renderer)};
    assert_true(light_gpu_update(lg, &src, sun, &s, LIGHT_GPU_DENSE, NULL));
    assert_true(light_gpu_read(lg, map));
    size_t count = (size_t)map->grid.n[0] * map->grid.n[1] * map->grid.n[2];
    for (size_t i = 0; i < count; i++)
        assert_true(isfinite(map->light[i]) && map->light[i] >= 0.0f && map->light[i] <= 1.0f);
    assert_true(multiple == (map->diffuse != NULL));
    light_gpu_destroy(lg);
}

static void gpu_light_map(const struct config *cfg, bool forward, struct light_map *map)
{
    gpu_light_map_with(cfg, forward, true, false, map);
}

/* ---- optically very thick ------------------------------------------------------------ */

static void test_very_thick(void **state)
{
    /* Column tau 1e4 over 8 voxels: about 625 per half-voxel step of the eye pass. */
    struct config cfg;
    struct ext_volume vol = {0};
    const char *sets[] = {"scene.kind=slab", "scene.size=[16,16,8]", "scene.extent=[10,10,1]",
                          "scene.tau=10000", "render.sky=[0,0,0]", "render.ground_on=false",
                          "light.elevation=45", "light.color=[1,1,1]", "light.intensity=1",
                          "camera.position=[5,-12,3]", "camera.target=[5,5,0.5]",
                          "render.width=32", "render.height=32",
                          "lightmap.resolution=[24,24,32]"};
    test_config_from(&cfg, sets, 14);
    test_upload_scene(renderer, &cfg, &vol);
    float bound = phase_max(&cfg.optics.params) * 1.0001f;
    struct image img;
    double eye[3] = {5e3, 5e3, 6e3}, target[3] = {5e3, 5e3, 0}, up[3] = {0, 1, 0};
    struct render_view top;
    camera_look_at(eye, target, up, 50.0, 10.0, 1e6, 32, 32, &top);
    for (int light = 0; light < 2; light++) {
        draw(&cfg, NULL, light, &img); /* from the side, grazing the top face */
        assert_bounded(&img, bound);
        image_finish(&img);
        /* From above every ray meets the slab: nothing behind it is seen. */
        draw(&cfg, &top, light, &img);
        assert_bounded(&img, bound);
        for (int i = 0; i < img.width * img.height; i++)
            assert_true(img.rgba[4 * i + 3] == 0.0f);
        image_finish(&img);
    }
    /* Light map: finite, in [0, 1], shadow-only non-increasing along the light. */
    struct light_map map = {0};
    gpu_light_map(&cfg, false, &map);
    const int *n = map.grid.n;
    for (int k = 1; k < n[2]; k++)
        for (int j = 0; j < n[1]; j++)
            for (int i = 0; i < n[0]; i++)
                assert_true(light_map_node(&map, i, j, k) <= light_map_node(&map, i, j, k - 1));
    assert_true(light_map_node(&map, n[0] / 2, n[1] / 2, n[2] - 1) == 0.0f);
    light_map_finish(&map);
    gpu_light_map(&cfg, true, &map);
    light_map_finish(&map);
    ext_volume_finish(&vol);
}

/* Multiple scattering through the same slab (column tau 1e4 overhead, 1.4e4 at 45 degrees;
 * per light slice 320 and 2500): the GPU column pass keeps every M and N finite with M >= 0
 * and |N| <= M; with the peripheral ring off no light leaves a column, so each column still
 * returns what it received (reflected + diffuse through + beam = 1); the eye pass stays finite
 * and within the bound the diffuse term allows. */
static void test_very_thick_diffuse(void **state)
{
    static const char *suns[][2] = {{"light.elevation=90", "light.azimuth=0"},
                                    {"light.elevation=45", "light.azimuth=210"}};
    for (size_t sun = 0; sun < 2; sun++) {
        struct config cfg;
        struct ext_volume vol = {0};
        const char *sets[] = {"scene.kind=slab", "scene.size=[16,16,8]", "scene.extent=[10,10,1]",
                              "scene.tau=10000", "render.sky=[0,0,0]", "render.ground_on=false",
                              "light.color=[1,1,1]", "light.intensity=1",
                              "camera.position=[5,-12,3]", "camera.target=[5,5,0.5]",
                              "render.width=32", "render.height=32",
                              "lightmap.resolution=[24,24,32]", "effects.multiple=on",
                              suns[sun][0], suns[sun][1]};
        test_config_from(&cfg, sets, 16);
        test_upload_scene(renderer, &cfg, &vol);
        double mmax = 0.0;
        for (int mode = 0; mode < 3; mode++) { /* shadow only, central, central + ring */
            struct light_map map = {0};
            gpu_light_map_with(&cfg, mode > 0, mode > 1, true, &map);
            const int *n = map.grid.n;
            size_t plane = (size_t)n[0] * n[1], count = plane * n[2];
            for (size_t i = 0; i < count; i++) {
                float m = map.diffuse[2 * i], nn = map.diffuse[2 * i + 1];
                if (!(isfinite(m) && isfinite(nn) && m >= 0.0f && fabsf(nn) <= m + 1e-6f))
                    fail_msg("sun %zu mode %d node %zu: M %g N %g", sun, mode, i, (double)m,
                             (double)nn);
                mmax = fmax(mmax, m);
            }
            if (mode < 2) {
                /* Per unit horizontal area a column receives mu0 = sin(elevation). */
                double mu0 = sun == 0 ? 1.0 : sin(M_PI / 4.0), worst = 0.0;
                for (size_t c = 0; c < plane; c++) {
                    double sum = mu0 * map.light[c + plane * (n[2] - 1)] +
                                 0.5 * map.diffuse[2 * c] +
                                 0.5 * map.diffuse[2 * (c + plane * (n[2] - 1))];
                    worst = fmax(worst, fabs(sum / mu0 - 1.0));
                }
                assert_true(worst <= 1e-3);
            }
            /* Overhead, the centre column crosses all 1 km: it reflects nearly everything. */
            if (sun == 0)
                assert_true(map.diffuse[2 * (n[0] / 2 + (size_t)n[0] * (n[1] / 2))] > 1.8f);
            light_map_finish(&map);
        }
        /* The eye pass: sum T (1 - T_s) <= 1 of P_v L_l + M + 1.5 g N mu_eye, |g| < 1. */
        float bound = (float)(phase_max(&cfg.optics.params) + 2.5 * mmax) * 1.0001f;
        struct image img;
        double eye[3] = {5e3, 5e3, 6e3}, target[3] = {5e3, 5e3, 0}, up[3] = {0, 1, 0};
        struct render_view top;
        camera_look_at(eye, target, up, 50.0, 10.0, 1e6, 32, 32, &top);
        draw(&cfg, NULL, true, &img);
        assert_bounded(&img, bound);
        image_finish(&img);
        draw(&cfg, &top, true, &img);
        assert_bounded(&img, bound);
        for (int i = 0; i < img.width * img.height; i++)
            assert_true(img.rgba[4 * i + 3] == 0.0f);
        /* The diffuse term really ran: from above, the slab's reflected light shows. */
        struct image single;
        assert_true(config_set(&cfg, "effects.multiple=off"));
        draw(&cfg, &top, true, &single);
        double with = 0.0, without = 0.0;
        for (int i = 0; i < img.width * img.height; i++) {
            with += img.rgba[4 * i];
            without += single.rgba[4 * i];
        }
        print_message("slab tau 1e4, sun %s: max M %.3g; from above, mean radiance with "
                      "multiple scattering %.4g, without %.4g\n",
                      suns[sun][0], mmax, with / (img.width * img.height),
                      without / (img.width * img.height));
        assert_true(with > 2.0 * without);
        image_finish(&single);
        image_finish(&img);
        ext_volume_finish(&vol);
    }
}

/* ---- empty volume ----------------------------------------------------------------------- */

static void test_empty_light_map_is_one(void **state)
{
    struct config cfg;
    struct ext_volume vol = {0};
    const char *sets[] = {"scene.kind=empty", "scene.size=[8,8,8]",
                          "lightmap.resolution=[16,16,16]"};
    test_config_from(&cfg, sets, 3);
    test_upload_scene(renderer, &cfg, &vol);
    struct light_map map = {0};
    gpu_light_map(&cfg, true, &map);
    size_t count = (size_t)16 * 16 * 16;
    for (size_t i = 0; i < count; i++)
        assert_true(map.light[i] == 1.0f);
    light_map_finish(&map);
    ext_volume_finish(&vol);
}

/* ---- one voxel -------------------------------------------------------------------------- */

/* Transmittance of the centre pixel of an odd-sized image looking straight down from high
 * above (X, Y) km: its ray is exactly vertical. */
static double centre_transmittance(const struct config *cfg, double x_km, double y_km, bool light)
{
    double eye[3] = {x_km * 1e3, y_km * 1e3, 40e3}, target[3] = {x_km * 1e3, y_km * 1e3, 0};
    double up[3] = {0, 1, 0};
    struct render_view v;
    camera_look_at(eye, target, up, 10.0, 10.0, 1e6, 33, 33, &v);
    struct image img;
    draw(cfg, &v, light, &img);
    double t = img.rgba[4 * (16 * 33 + 16) + 3];
    image_finish(&img);
    return t;
}

static void test_single_voxel(void **state)
{
    /* A grid of one voxel: a homogeneous box; straight down through it, e^-tau. */
    struct config cfg;
    struct ext_volume vol = {0};
    const char *one[] = {"scene.kind=slab", "scene.size=[1,1,1]", "scene.extent=[10,10,1]",
                         "scene.tau=2", "render.ground_on=false",
                         "lightmap.resolution=[8,8,8]"};
    test_config_from(&cfg, one, 6);
    test_upload_scene(renderer, &cfg, &vol);
    for (int light = 0; light < 2; light++)
        assert_float_equal(centre_transmittance(&cfg, 5.0, 5.0, light), exp(-2.0),
                           1e-3 * exp(-2.0));
    ext_volume_finish(&vol);

    /* One non-empty voxel in 5^3: trilinear filtering makes a tent one voxel wide each way;
     * half-voxel midpoint steps aligned with the voxel centres integrate it exactly, so
     * straight down through its centre the optical depth is tau again (to 0.5 %: float
     * rounding of the path length may add one step, which shifts the samples). */
    const char *voxel[] = {"scene.kind=voxel", "scene.size=[5,5,5]", "scene.extent=[5,5,5]",
                           "scene.tau=1.5", "render.ground_on=false",
                           "lightmap.resolution=[12,12,12]", "light.elevation=60"};
    test_config_from(&cfg, voxel, 7);
    test_upload_scene(renderer, &cfg, &vol);
    for (int light = 0; light < 2; light++)
        assert_float_equal(centre_transmittance(&cfg, 2.5, 2.5, light), exp(-1.5),
                           5e-3 * exp(-1.5));
    struct light_map map = {0};
    gpu_light_map(&cfg, true, &map);
    light_map_finish(&map);
    struct image img;
    draw(&cfg, NULL, true, &img);
    assert_int_equal(image_count_nonfinite(&img), 0);
    image_finish(&img);
    ext_volume_finish(&vol);
}

/* ---- sun along an axis and at grazing angles -------------------------------------------- */

static void test_axis_and_grazing_sun(void **state)
{
    static const char *suns[][2] = {
        {"light.elevation=90", "light.azimuth=0"},   {"light.elevation=0", "light.azimuth=90"},
        {"light.elevation=0", "light.azimuth=0"},    {"light.elevation=0.001", "light.azimuth=45"},
        {"light.elevation=-0.001", "light.azimuth=180"},
        {"light.elevation=89.999", "light.azimuth=0"},
    };
    for (size_t s = 0; s < sizeof(suns) / sizeof(suns[0]); s++) {
        struct config cfg;
        struct ext_volume vol = {0};
        const char *sets[] = {"scene.kind=sphere", "scene.size=[16,16,16]",
                              "scene.extent=[10,10,10]", "scene.tau=8",
                              "camera.position=[5,-20,5]", "camera.target=[5,5,5]",
                              "render.width=24", "render.height=24", "light.color=[1,1,1]",
                              "light.intensity=1", "render.sky=[0,0,0]",
                              "lightmap.resolution=[16,16,24]", suns[s][0], suns[s][1]};
        test_config_from(&cfg, sets, 14);
        test_upload_scene(renderer, &cfg, &vol);
        struct light_map map = {0};
        gpu_light_map(&cfg, true, &map);
        light_map_finish(&map);
        struct image img;
        draw(&cfg, NULL, true, &img);
        /* Ground: albedo (4 L_sun sin(el) + sky) <= 4 * 0.05; the volume: phase max. */
        assert_bounded(&img, fmaxf(phase_max(&cfg.optics.params), 0.2f) * 1.0001f);
        image_finish(&img);
        ext_volume_finish(&vol);
    }
}

/* ---- cameras on a face, an edge, a corner, across the near plane, inside ---------------- */

/* Transmittance of the centre pixel (33 x 33, vertical field 2 degrees) looking from EYE
 * toward TARGET (km), near plane NEAR_M. */
static double look(const struct config *cfg, const double eye_km[3], const double target_km[3],
                   double near_m, struct image *keep)
{
    double eye[3], target[3], up[3] = {0, 1, 0};
    for (int a = 0; a < 3; a++) {
        eye[a] = eye_km[a] * 1e3;
        target[a] = target_km[a] * 1e3;
    }
    if (fabs(eye[0] - target[0]) + fabs(eye[1] - target[1]) > 0)
        up[0] = 0, up[1] = 0, up[2] = 1;
    struct render_view v;
    camera_look_at(eye, target, up, 2.0, near_m, 1e6, 33, 33, &v);
    struct image img;
    draw(cfg, &v, true, &img);
    assert_bounded(&img, 1.0001); /* sky 1, no sun: transmittance times 1 */
    double t = img.rgba[4 * (16 * 33 + 16) + 3];
    assert_float_equal(img.rgba[4 * (16 * 33 + 16)], t, 1e-6);
    if (keep)
        *keep = img;
    else
        image_finish(&img);
    return t;
}

static void test_camera_on_faces_edges_inside(void **state)
{
    /* A 10 x 10 x 1 km slab of tau 2 (beta 2e-3 / m), lit by a sky of 1 and no sun: every
     * pixel is the transmittance from its near-plane point to the far face. */
    struct config cfg;
    struct ext_volume vol = {0};
    const char *sets[] = {"scene.kind=slab", "scene.size=[16,16,8]", "scene.extent=[10,10,1]",
                          "scene.tau=2", "light.intensity=0", "render.ground_on=false",
                          "render.sky=[1,1,1]", "lightmap.resolution=[8,8,8]"};
    test_config_from(&cfg, sets, 8);
    test_upload_scene(renderer, &cfg, &vol);
    const double beta = 2e-3;
    double down[3] = {5, 5, -10};
    /* On the top face, near plane 1 m: 999 m of medium. */
    double face[3] = {5, 5, 1};
    assert_float_equal(look(&cfg, face, down, 1.0, NULL), exp(-beta * 999.0), 1e-3);
    /* Just outside the face by 0.5 m, near plane 1 m: the near plane is inside already. */
    double outside[3] = {5, 5, 1.0005};
    assert_float_equal(look(&cfg, outside, down, 1.0, NULL), exp(-beta * 999.5), 1e-3);
    /* Inside, at mid-height: 500 m below the eye, less the near plane. */
    double inside[3] = {5, 5, 0.5};
    assert_float_equal(look(&cfg, inside, down, 1.0, NULL), exp(-beta * 499.0), 1e-3);
    /* On the bottom face looking up: the whole slab but the near plane. */
    double bottom[3] = {5, 5, 0}, up_target[3] = {5, 5, 10};
    assert_float_equal(look(&cfg, bottom, up_target, 1.0, NULL), exp(-beta * 999.0), 1e-3);
    /* Below the bottom face looking down: nothing in front, exactly the sky. */
    double below[3] = {5, 5, -0.0005};
    assert_float_equal(look(&cfg, below, down, 1.0, NULL), 1.0, 0.0);
    /* On an edge (x = 0, z = 1 km) looking straight down: half the image sees the slab (rays
     * toward x > 0), half sees past it; the centre ray grazes the face x = 0. */
    double edge[3] = {0, 5, 1}, edge_down[3] = {0, 5, -10};
    struct image img;
    look(&cfg, edge, edge_down, 1.0, &img);
    int inside_rays = 0, outside_rays = 0;
    for (int y = 0; y < 33; y++) {
        for (int x = 0; x < 33; x++) {
            float t = img.rgba[4 * (y * 33 + x) + 3];
            if (x < 16) /* image x grows with world x for this camera (up = +y) */
                outside_rays += t == 1.0f;
            else if (x > 16)
                inside_rays += fabs(t - exp(-beta * 999.0)) < 2e-3;
        }
    }
    image_finish(&img);
    assert_int_equal(inside_rays + outside_rays, 2 * 16 * 33);
    /* On a corner looking along the diagonal into the box: finite and bounded (asserted in
     * look), and the medium is seen. */
    double corner[3] = {0, 0, 1}, diag[3] = {10, 10, 0};
    assert_true(look(&cfg, corner, diag, 1.0, NULL) < 0.5);
    ext_volume_finish(&vol);
}

/* ---- |g| -> 1 ---------------------------------------------------------------------------- */

static void test_extreme_asymmetry(void **state)
{
    struct config cfg;
    struct ext_volume vol = {0};
    const char *sets[] = {"scene.kind=sphere", "scene.size=[16,16,16]",
                          "scene.extent=[10,10,10]", "scene.tau=6", "light.azimuth=180",
                          "light.elevation=10", "camera.position=[5,-20,5]",
                          "camera.target=[5,5,5]", "render.width=24", "render.height=24",
                          "render.ground_on=false", "lightmap.resolution=[16,16,16]"};
    static const double gs[][2] = {{0.999, -0.999}, {1.0, -1.0}, {-1.0, 1.0}, {0.9999, 0.9999}};
    for (size_t i = 0; i < sizeof(gs) / sizeof(gs[0]); i++) {
        test_config_from(&cfg, sets, 12);
        /* Beyond the config's range (-0.9, 0.9): set directly. */
        cfg.optics.params.g_water = gs[i][0];
        cfg.optics.params.g_ice = gs[i][1];
        test_upload_scene(renderer, &cfg, &vol);
        struct light_settings s;
        light_settings_defaults(&s);
        light_settings_set_optics(&s, &cfg.optics.params, 20.0);
        assert_true(isfinite(s.cp.water_ctr) && isfinite(s.cp.ice_per));
        assert_true(s.cp.water_ctr >= 0 && s.cp.water_ctr + s.cp.water_per <= 1.0 + 1e-9);
        assert_true(s.cp.ice_ctr >= 0 && s.cp.ice_ctr + s.cp.ice_per <= 1.0 + 1e-9);
        struct light_map map = {0};
        gpu_light_map(&cfg, true, &map);
        light_map_finish(&map);
        struct image img;
        draw(&cfg, NULL, true, &img);
        float sky = (float)fmax(cfg.render.sky[0], fmax(cfg.render.sky[1], cfg.render.sky[2]));
        float sun = (float)(cfg.light.intensity * 1.0);
        assert_bounded(&img, phase_max(&cfg.optics.params) * sun * 1.0001f + sky);
        image_finish(&img);
        ext_volume_finish(&vol);
    }
}

/* ---- fp16 -------------------------------------------------------------------------------- */

static void test_fp16_storage(void **state)
{
    /* By default extinction is stored as 32-bit float whatever its size: 1e6 / m (beyond half
     * precision's 65504) round-trips exactly through the renderer's texture. */
    struct grid3 g = {.n = {2, 2, 2}, .origin = {0, 0, 0}, .spacing = {1, 1, 1}};
    struct ext_volume vol = {0};
    assert_true(ext_volume_init(&vol, &g));
    for (int i = 0; i < 8; i++) {
        vol.beta[2 * i] = 1e6f;
        vol.beta[2 * i + 1] = i == 0 ? INFINITY : i == 1 ? NAN : i == 2 ? -5.0f : 3e-3f;
    }
    assert_true(renderer_set_volume(renderer, &vol));
    const struct gpu_texture *t = renderer_volume_texture(renderer);
    assert_int_equal(t->format, GPU_RG32F);
    float back[16];
    gpu_texture_read(t, back, sizeof(back));
    for (int i = 0; i < 8; i++)
        assert_true(back[2 * i] == 1e6f);
    /* Half floats (render.precision = "half"): what lies beyond 65504 clamps to it, never to
     * infinity; infinity too; NaN and negative stay what they were (they read as 0); the rest
     * keeps three digits. */
    renderer_set_half(renderer, true);
    assert_true(renderer_set_volume(renderer, &vol));
    t = renderer_volume_texture(renderer);
    assert_int_equal(t->format, GPU_RG16F);
    gpu_texture_read(t, back, sizeof(back));
    for (int i = 0; i < 8; i++)
        assert_true(back[2 * i] == RENDER_HALF_MAX);
    assert_true(back[1] == RENDER_HALF_MAX);
    assert_true(isnan(back[3]));
    assert_true(back[5] == -5.0f);
    for (int i = 3; i < 8; i++)
        assert_float_equal(back[2 * i + 1], 3e-3f, 3e-3f * 1e-3f);
    /* Without the clamp the GPU would have stored what is no value: infinity or less. */
    struct gpu_texture half = {0};
    int size[3] = {2, 2, 2};
    assert_true(gpu_texture_init(&half, 3, size, GPU_RG16F, vol.beta));
    float h[16];
    gpu_texture_read(&half, h, sizeof(h));
    assert_true(h[0] != 1e6f && (isinf(h[0]) || h[0] <= 65504.0f));
    gpu_texture_finish(&half);
    ext_volume_finish(&vol);

    /* The clamped extinction in a picture: a slab of 1e5 / m (optical depth 1e6 through its
     * 10 m) in half floats with a half-float light map is as black as in floats: finite, no
     * light through it, the sky around it. */
    struct config cfg;
    const char *sets[] = {"scene.kind=slab",         "scene.size=[8,8,4]",
                          "scene.extent=[0.1,0.1,0.01]", "scene.tau=1e6",
                          "camera.position=[0.05,-0.15,0.06]",
                          "camera.target=[0.05,0.05,0.005]", "render.width=32",
                          "render.height=32", "render.precision=half", "render.sky=[1,1,1]"};
    test_config_from(&cfg, sets, 10);
    renderer_set_half(renderer, true);
    test_upload_scene(renderer, &cfg, &vol);
    assert_true(vol.beta[0] + vol.beta[1] > RENDER_HALF_MAX); /* it is clamped */
    struct image img[2];
    draw(&cfg, NULL, true, &img[0]);
    renderer_set_half(renderer, false);
    cfg.render.precision = PRECISION_FLOAT;
    assert_true(renderer_set_volume(renderer, &vol));
    draw(&cfg, NULL, true, &img[1]);
    int blocked = 0;
    for (int i = 0; i < 32 * 32; i++) {
        for (int c = 0; c < 4; c++)
            assert_true(isfinite(img[0].rgba[4 * i + c]));
        assert_float_equal(img[0].rgba[4 * i + 3], img[1].rgba[4 * i + 3], 1e-6);
        blocked += img[0].rgba[4 * i + 3] == 0.0f;
    }
    assert_true(blocked > 100); /* the slab is seen, and nothing passes it */
    image_finish(&img[0]);
    image_finish(&img[1]);
    ext_volume_finish(&vol);
}

/* ---- bad extinction values in the eye pass ---------------------------------------------- */

static void test_bad_values_in_the_volume(void **state)
{
    /* The readers clean NaN, Inf, negative and fill values, but the eye pass and the light
     * pass must not turn one that slips through into a NaN image: they read as empty (NaN,
     * negative) or as the largest float (Inf). */
    struct config cfg;
    const char *sets[] = {"scene.kind=slab", "scene.size=[4,4,4]", "scene.extent=[4,4,4]",
                          "camera.position=[2,-10,2]", "camera.target=[2,2,2]",
                          "render.width=16", "render.height=16", "render.ground_on=false",
                          "lightmap.resolution=[8,8,8]"};
    test_config_from(&cfg, sets, 9);
    struct ext_volume vol = {0};
    assert_true(scene_build_volume(&cfg, &vol));
    const float bad[] = {NAN, INFINITY, -1.0f, -INFINITY, 9.96921e36f};
    for (int i = 0; i < 64; i++) {
        vol.beta[2 * i] = bad[i % 5];
        vol.beta[2 * i + 1] = i % 3 ? 1e-3f : bad[(i + 2) % 5];
    }
    assert_true(renderer_set_volume(renderer, &vol));
    struct light_map map = {0};
    gpu_light_map(&cfg, true, &map);
    light_map_finish(&map);
    struct image img;
    for (int light = 0; light < 2; light++) {
        draw(&cfg, NULL, light, &img);
        assert_int_equal(image_count_nonfinite(&img), 0);
        for (int i = 0; i < 16 * 16 * 4; i++)
            assert_true(img.rgba[i] >= 0.0f);
        image_finish(&img);
    }
    ext_volume_finish(&vol);
}

/* ---- extreme aspect ratios ---------------------------------------------------------------- */

static void test_extreme_aspect(void **state)
{
    /* 1000 x 1000 x 1 km on 64 x 64 x 2 voxels: straight down, e^-tau; the light map at a low
     * sun (sub-steps at their cap) matches the CPU reference. */
    struct config cfg;
    struct ext_volume vol = {0};
    const char *flat[] = {"scene.kind=slab", "scene.size=[64,64,2]",
                          "scene.extent=[1000,1000,1]", "scene.tau=2",
                          "render.ground_on=false", "light.elevation=5", "light.azimuth=30",
                          "lightmap.resolution=[32,32,32]"};
    test_config_from(&cfg, flat, 8);
    test_upload_scene(renderer, &cfg, &vol);
    for (int light = 0; light < 2; light++)
        assert_float_equal(centre_transmittance(&cfg, 500.0, 500.0, light), exp(-2.0),
                           1e-3 * exp(-2.0));
    struct light_map gpu = {0}, cpu = {0};
    gpu_light_map(&cfg, true, &gpu);
    struct light_settings s;
    light_settings_defaults(&s);
    memcpy(s.resolution, cfg.lightmap.resolution, sizeof(s.resolution));
    light_settings_set_optics(&s, &cfg.optics.params, cfg.lightmap.forward_angle_deg);
    double sun[3];
    light_sun_direction(cfg.light.azimuth_deg, cfg.light.elevation_deg, sun);
    assert_true(light_map_build(&vol, sun, &s, &cpu));
    size_t count = (size_t)32 * 32 * 32;
    double worst = 0.0, lo = 1.0;
    for (size_t i = 0; i < count; i++) {
        worst = fmax(worst, fabs((double)gpu.light[i] - cpu.light[i]));
        lo = fmin(lo, cpu.light[i]);
    }
    assert_true(lo < 0.5);
    assert_true(worst < 1e-3);
    light_map_finish(&gpu);
    light_map_finish(&cpu);
    ext_volume_finish(&vol);

    /* A 1 x 1 x 1000 km column seen from the side: finite and bounded. */
    const char *tall[] = {"scene.kind=slab", "scene.size=[2,2,64]", "scene.extent=[1,1,1000]",
                          "scene.tau=5", "camera.position=[0.5,-20,500]",
                          "camera.target=[0.5,0.5,500]", "render.width=16", "render.height=16",
                          "render.ground_on=false", "render.sky=[0,0,0]", "light.color=[1,1,1]",
                          "light.intensity=1", "lightmap.resolution=[16,16,16]"};
    test_config_from(&cfg, tall, 13);
    test_upload_scene(renderer, &cfg, &vol);
    struct image img;
    draw(&cfg, NULL, true, &img);
    assert_bounded(&img, phase_max(&cfg.optics.params) * 1.0001f);
    image_finish(&img);
    ext_volume_finish(&vol);
}

int main(void)
{
    log_set_level(LOG_ERROR);
    ctx = test_gl_context_or_skip();
    renderer = renderer_create();
    if (!renderer)
        return 1;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_very_thick),
        cmocka_unit_test(test_very_thick_diffuse),
        cmocka_unit_test(test_empty_light_map_is_one),
        cmocka_unit_test(test_single_voxel),
        cmocka_unit_test(test_axis_and_grazing_sun),
        cmocka_unit_test(test_camera_on_faces_edges_inside),
        cmocka_unit_test(test_extreme_asymmetry),
        cmocka_unit_test(test_fp16_storage),
        cmocka_unit_test(test_bad_values_in_the_volume),
        cmocka_unit_test(test_extreme_aspect),
    };
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    renderer_destroy(renderer);
    gpu_context_destroy(ctx);
    return rc;
}
