/*
 * What a path on the command line is (data/detect), and the views that frame a scene of data
 * without a camera: the orbit camera (the domain's eight corners inside the image, covering a
 * third of it at least) and a tracked display's navigation fitted to its room, against the
 * sample WRF files (skipped where they are absent).
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <cmocka.h>

#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <netcdf.h>

#include "app/app.h"
#include "common/log.h"
#include "config/config.h"
#include "config/display_config.h"
#include "data/detect.h"
#include "data/source.h"
#include "data/synth.h"
#include "data/wrf.h"
#include "data/wrf_write.h"
#include "display/display.h"
#include "render/camera.h"
#include "session/scene.h"

#define KATRINA "wrf/katrina_2005_mercator_wsm3.nc"
#define LAMBERT "wrf/lambert_thompson_cropped.nc"

static const char *sample_or_skip(const char *name)
{
    const char *p = test_shared_data(name);
    struct stat st;
    if (stat(p, &st) != 0)
        skip();
    return p;
}

/* ---- detection --------------------------------------------------------------------------- */

static void test_detect(void **state)
{
    (void)state;
    char why[2048];
    /* A text file is a config; an empty one is refused (a failed download is not a scene). */
    assert_int_equal(data_detect(test_write_file("look.cfg", "light = { elevation = 20.0; };\n"),
                                 why, sizeof(why)),
                     DATA_KIND_CONFIG);
    assert_string_equal(why, "");
    assert_int_equal(data_detect(test_write_file("empty.nc", ""), why, sizeof(why)),
                     DATA_KIND_UNKNOWN);
    assert_non_null(strstr(why, "an empty file"));
    /* Binary, not NetCDF: its first bytes, a hint for gzip. */
    const char *gz = test_tmp_path("wrfout.nc.gz");
    char gzp[512];
    snprintf(gzp, sizeof(gzp), "%s", gz);
    FILE *f = fopen(gzp, "wb");
    assert_non_null(f);
    fwrite("\x1f\x8b\x08\x00\x00\x00\x00\x00\x00\x03", 1, 10, f);
    fclose(f);
    assert_int_equal(data_detect(gzp, why, sizeof(why)), DATA_KIND_UNKNOWN);
    assert_non_null(strstr(why, "1f 8b 08 00"));
    assert_non_null(strstr(why, "gzip"));
    /* A NetCDF file of another kind: what it has, and what was expected. */
    char other[512];
    snprintf(other, sizeof(other), "%s", test_tmp_path("era5.nc"));
    int nc, dl, dt, var;
    assert_int_equal(nc_create(other, NC_CLOBBER | NC_64BIT_OFFSET, &nc), NC_NOERR);
    assert_int_equal(nc_def_dim(nc, "latitude", 3, &dl), NC_NOERR);
    assert_int_equal(nc_def_dim(nc, "time", 2, &dt), NC_NOERR);
    assert_int_equal(nc_def_var(nc, "t2m", NC_FLOAT, 1, &dl, &var), NC_NOERR);
    assert_int_equal(nc_enddef(nc), NC_NOERR);
    assert_int_equal(nc_close(nc), NC_NOERR);
    assert_int_equal(data_detect(other, why, sizeof(why)), DATA_KIND_UNKNOWN);
    assert_non_null(strstr(why, other));
    assert_non_null(strstr(why, "latitude, time"));
    assert_non_null(strstr(why, "t2m"));
    assert_non_null(strstr(why, "expected WRF output"));
    /* A folder: Isabel bricks, or nothing anvil reads. */
    char dir[512];
    snprintf(dir, sizeof(dir), "%s", test_tmp_path("isabel"));
    assert_int_equal(mkdir(dir, 0700), 0);
    assert_int_equal(data_detect(dir, why, sizeof(why)), DATA_KIND_UNKNOWN);
    assert_non_null(strstr(why, "QCLOUDf01.bin"));
    test_write_file("isabel/QCLOUDf01.bin", "....");
    assert_int_equal(data_detect(dir, why, sizeof(why)), DATA_KIND_ISABEL);
    /* Missing. */
    assert_int_equal(data_detect("/nonexistent/wrfout", why, sizeof(why)), DATA_KIND_UNREADABLE);
    assert_non_null(strstr(why, "/nonexistent/wrfout"));
    /* The samples are WRF output. */
    assert_int_equal(data_detect(sample_or_skip(KATRINA), why, sizeof(why)), DATA_KIND_WRF);
    assert_int_equal(data_detect(sample_or_skip(LAMBERT), why, sizeof(why)), DATA_KIND_WRF);
}

/* ---- the orbit camera -------------------------------------------------------------------- */

/* The pixel rectangle the eight corners of LO..HI project to with CFG's camera; false when
 * one lies behind the eye or outside the image. */
static bool corners_in_image(const struct config *cfg, const double lo[3], const double hi[3],
                             double *covered)
{
    struct render_view v;
    scene_camera_view(cfg, cfg->render.width, cfg->render.height, &v);
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
    bool inside = true;
    for (int c = 0; c < 8; c++) {
        double p[4] = {c & 1 ? hi[0] : lo[0], c & 2 ? hi[1] : lo[1], c & 4 ? hi[2] : lo[2], 1};
        double e[4] = {0}, clip[4] = {0};
        for (int r = 0; r < 4; r++)
            for (int k = 0; k < 4; k++)
                e[r] += v.view[k * 4 + r] * p[k]; /* column-major */
        for (int r = 0; r < 4; r++)
            for (int k = 0; k < 4; k++)
                clip[r] += v.proj[k * 4 + r] * e[k];
        if (!(clip[3] > 0.0)) {
            inside = false;
            continue;
        }
        double nx = clip[0] / clip[3], ny = clip[1] / clip[3];
        inside = inside && fabs(nx) <= 1.0 && fabs(ny) <= 1.0;
        x0 = fmin(x0, nx), x1 = fmax(x1, nx), y0 = fmin(y0, ny), y1 = fmax(y1, ny);
    }
    /* The share of the image inside the corners' rectangle (clipped to the image). */
    *covered = (fmin(x1, 1.0) - fmax(x0, -1.0)) * (fmin(y1, 1.0) - fmax(y0, -1.0)) / 4.0;
    return inside;
}

static void check_framed(const char *name)
{
    const char *path = sample_or_skip(name);
    char arg[1024];
    snprintf(arg, sizeof(arg), "%s", path);
    char *args[] = {arg};
    static struct config cfg, plain;
    assert_int_equal(app_load_scene("render", args, 1, NULL, 0, &cfg, NULL), EXIT_OK);
    assert_int_equal(cfg.scene.kind, SCENE_DATA);
    assert_int_equal(cfg.data.format, DATA_WRF);
    assert_false(cfg.camera.given);
    double lo[3], hi[3];
    assert_true(scene_domain_box(&cfg, lo, hi));

    /* The box is the volume's: the grid the reader puts a step on. */
    struct ext_volume vol;
    assert_true(scene_build_volume(&cfg, &vol));
    for (int a = 0; a < 3; a++) {
        assert_true(fabs(vol.grid.origin[a] - lo[a]) < 1e-6 * (hi[a] - lo[a]));
        double top = vol.grid.origin[a] + vol.grid.n[a] * vol.grid.spacing[a];
        assert_true(fabs(top - hi[a]) < 1e-6 * (hi[a] - lo[a]));
    }
    ext_volume_finish(&vol);

    double covered;
    if (!corners_in_image(&cfg, lo, hi, &covered))
        fail_msg("%s: a corner of the domain lies outside the framed picture", name);
    if (!(covered >= 1.0 / 3.0))
        fail_msg("%s: the domain covers %.2f of the picture", name, covered);
    print_message("%s: %.0f x %.0f x %.1f km framed, covering %.2f of the picture\n", name,
                  (hi[0] - lo[0]) / 1e3, (hi[1] - lo[1]) / 1e3, (hi[2] - lo[2]) / 1e3, covered);
    /* From the south-west (eye west and south of the target), 30 degrees up. */
    const struct config_camera *c = &cfg.camera;
    double d[3];
    for (int i = 0; i < 3; i++)
        d[i] = c->position_km[i] - c->target_km[i];
    assert_true(d[0] < 0.0 && d[1] < 0.0 && fabs(d[0] - d[1]) < 1e-9 * fabs(d[0]));
    double el = atan2(d[2], hypot(d[0], d[1])) * 180.0 / M_PI;
    assert_true(fabs(el - 30.0) < 1e-9);

    /* The built-in storm's camera (what a scene of data had before) leaves corners out. */
    plain = cfg;
    config_defaults(&plain);
    plain.camera.given = true;
    memcpy(&plain.data, &cfg.data, sizeof(plain.data));
    plain.scene.kind = SCENE_DATA;
    assert_false(corners_in_image(&plain, lo, hi, &covered));

    /* A camera given (any camera.* setting) is kept. */
    char *sets[] = {"camera.fov=30"};
    assert_int_equal(app_load_scene("render", args, 1, sets, 1, &cfg, NULL), EXIT_OK);
    assert_true(cfg.camera.given);
    assert_true(cfg.camera.position_km[0] == 2.0 && cfg.camera.target_km[0] == 30.0);
}

static void test_frame_katrina(void **state)
{
    (void)state;
    check_framed(KATRINA);
}

static void test_frame_lambert(void **state)
{
    (void)state;
    check_framed(LAMBERT);
}

/* ---- the room ------------------------------------------------------------------------------ */

static void test_cave_fits_katrina(void **state)
{
    (void)state;
    const char *path = sample_or_skip(KATRINA);
    char arg[1024];
    snprintf(arg, sizeof(arg), "%s", path);
    char *args[] = {arg};
    static struct config cfg;
    assert_int_equal(app_load_scene("render", args, 1, NULL, 0, &cfg, NULL), EXIT_OK);
    static struct display_config dc;
    assert_true(display_config_load(ANVIL_SOURCE_DIR "/displays/cave4.cfg", &dc));
    assert_false(dc.navigation.given);
    struct display_navigation fit;
    assert_true(app_frame_navigation(&cfg, &dc, &fit));
    assert_memory_equal(&fit, &dc.navigation, sizeof(fit));
    double lo[3], hi[3];
    assert_true(scene_domain_box(&cfg, lo, hi));
    float m[16];
    display_navigation_matrix(&dc.navigation, m);
    /* The corners and the centre in the room (tracker metres: x right, y up, z back). */
    double rlo[3] = {INFINITY, INFINITY, INFINITY}, rhi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int c = 0; c < 9; c++) {
        double p[3];
        for (int i = 0; i < 3; i++)
            p[i] = c == 8 ? 0.5 * (lo[i] + hi[i]) : (c >> i & 1) ? hi[i] : lo[i];
        double t[3];
        for (int r = 0; r < 3; r++)
            t[r] = m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + m[12 + r];
        if (c == 8) {
            /* The centre straight ahead of the viewer (head [0, 1.6, 0.5], facing -z). */
            assert_true(fabs(t[0] - dc.head.position[0]) < 1e-3);
            assert_true(t[2] < dc.head.position[2] - 0.2);
            continue;
        }
        for (int i = 0; i < 3; i++)
            rlo[i] = fmin(rlo[i], t[i]), rhi[i] = fmax(rhi[i], t[i]);
    }
    print_message("Katrina in cave4: x %.2f..%.2f, y %.3f..%.3f, z %.2f..%.2f m (scale %.3g)\n",
                  rlo[0], rhi[0], rlo[1], rhi[1], rlo[2], rhi[2], dc.navigation.scale);
    /* Inside the 3 m cube of the walls, in front of the viewer, below the eyes. */
    assert_true(rlo[0] >= -1.5 - 1e-4 && rhi[0] <= 1.5 + 1e-4);
    assert_true(rlo[2] >= -1.5 - 1e-4 && rhi[2] <= dc.head.position[2] - 0.2 + 1e-4);
    assert_true(rlo[1] >= -1e-4 && rhi[1] <= dc.head.position[1] - 0.3 + 1e-4);
    /* And it fills the room: the depth from the front wall to the viewer (1.8 m). */
    assert_true(rhi[2] - rlo[2] > 1.7);

    /* The navigation that was shipped for the 60 km storm put Katrina far beyond the room. */
    struct display_navigation old = {.scale = 1e-4, .origin_km = {30, 30, 0},
                                     .position = {0, 0, -2}};
    display_navigation_matrix(&old, m);
    double far_corner = m[0] * hi[0] + m[12];
    assert_true(far_corner > 1.5);

    /* A navigation given is kept; the fit (what the frame key brings) is still made. */
    assert_true(display_config_set(&dc, "navigation.scale=1e-4"));
    assert_true(dc.navigation.given);
    dc.navigation.position[2] = -2.0;
    struct display_navigation again;
    assert_true(app_frame_navigation(&cfg, &dc, &again));
    assert_true(dc.navigation.scale == 1e-4 && dc.navigation.position[2] == -2.0);
    assert_true(again.scale == fit.scale && again.position[2] == fit.position[2]);
}

/* ---- integrity -------------------------------------------------------------------------- */

static void test_step_of_fill(void **state)
{
    (void)state;
    /* Three steps of the synthetic storm: whole; only fill values and zeros (a step the model
     * did not write); every value fill. */
    char path[512];
    snprintf(path, sizeof(path), "%s", test_tmp_path("gaps.nc"));
    struct synth_desc sd = {.kind = SYNTH_STORM, .n = {16, 16, 8}, .extent_m = {30e3, 30e3, 12e3},
                            .seed = 3, .time = 0.5};
    struct wrf_writer *w = NULL;
    for (int step = 0; step < 3; step++) {
        struct field_volume fv;
        assert_true(synth_storm_fields(&sd, &fv));
        size_t n = grid3_count(&fv.grid);
        for (int f = 0; step > 0 && f < SPECIES_COUNT; f++) {
            for (size_t i = 0; fv.q[f] && i < n; i++)
                fv.q[f][i] = step == 2 || i % 2 ? NC_FILL_FLOAT : 0.0f;
        }
        if (!w)
            w = wrf_writer_create(path, &fv.grid, NULL);
        assert_non_null(w);
        char date[32];
        snprintf(date, sizeof(date), "2000-01-01_0%d:00:00", step);
        assert_true(wrf_writer_add(w, &fv, date));
        field_volume_finish(&fv);
    }
    assert_true(wrf_writer_finish(w));
    const char *files[1] = {path};
    struct data_source_desc dd = {.format = DATA_SOURCE_WRF, .files = files, .file_count = 1};
    wrf_desc_defaults(&dd.wrf);
    optics_params_defaults(&dd.optics);
    species_select_defaults(&dd.select);
    struct data_source *src = data_source_open(&dd);
    assert_non_null(src);
    struct field_volume fv;
    unsigned warnings = log_warn_count();
    assert_true(data_source_load_fields(src, 0, &fv));
    field_volume_finish(&fv);
    assert_int_equal(log_warn_count(), warnings);
    /* Fill and zeros: loaded (clear sky), with a warning naming the file and the step. */
    assert_true(data_source_load_fields(src, 1, &fv));
    field_volume_finish(&fv);
    assert_true(log_warn_count() > warnings);
    const char *msg = log_last_warning();
    assert_non_null(strstr(msg, path));
    assert_non_null(strstr(msg, "time step 1 (2000-01-01_01:00:00)"));
    assert_non_null(strstr(msg, "no condensate"));
    /* Every value fill: refused, naming the step. */
    unsigned errors = log_error_count();
    assert_false(data_source_load_fields(src, 2, &fv));
    assert_true(log_error_count() > errors);
    assert_non_null(strstr(log_last_error(), "2000-01-01_02:00:00"));
    data_source_close(src);
}

int main(void)
{
    log_set_level(LOG_NONE);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_detect),
        cmocka_unit_test(test_frame_katrina),
        cmocka_unit_test(test_frame_lambert),
        cmocka_unit_test(test_cave_fits_katrina),
        cmocka_unit_test(test_step_of_fill),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
