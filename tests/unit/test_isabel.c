/* Isabel bricks: big-endian floats, land value, missing species, size mismatch. */
#include "testutil.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "common/log.h"
#include "data/geo.h"
#include "data/isabel.h"
#include "data/probe.h"
#include "data/source.h"
#include "data/wrf_write.h"

#define NX 6
#define NY 5
#define NZ 4
#define N (NX * NY * NZ)

static void write_brick(const char *dir, const char *field, int step, const float *v, size_t n)
{
    char path[1024];
    snprintf(path, sizeof(path), "%s/%sf%02d.bin", dir, field, step);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    for (size_t i = 0; i < n; i++) {
        uint32_t u;
        memcpy(&u, &v[i], 4);
        unsigned char b[4] = {(unsigned char)(u >> 24), (unsigned char)(u >> 16),
                              (unsigned char)(u >> 8), (unsigned char)u};
        fwrite(b, 1, 4, f);
    }
    fclose(f);
}

static const char *make_dir(const char *name)
{
    static char dir[512];
    snprintf(dir, sizeof(dir), "%s", test_tmp_path(name));
    mkdir(dir, 0755);
    return dir;
}

static void test_read(void **state)
{
    const char *dir = make_dir("isabel");
    float v[N];
    for (int step = 1; step <= 2; step++) {
        for (int i = 0; i < N; i++)
            v[i] = 1e-5f * (float)i + (float)step * 1e-3f;
        v[0] = ISABEL_LAND;
        v[1] = -2e-6f;
        v[2] = NAN;
        write_brick(dir, "QCLOUD", step, v, N);
        for (int i = 0; i < N; i++)
            v[i] = 2e-6f * (float)(N - i);
        write_brick(dir, "QSNOW", step, v, N);
    }
    struct isabel_desc d = {.dir = dir, .n = {NX, NY, NZ}, .extent_m = {60e3, 50e3, 2e3}};
    assert_int_equal(isabel_step_count(&d), 2);
    struct field_volume fv;
    struct isabel_stats st;
    assert_true(isabel_read_step(&d, 1, &fv, &st));
    assert_int_equal(fv.grid.n[0], NX);
    assert_int_equal(fv.grid.n[2], NZ);
    assert_float_equal(fv.grid.spacing[0], 10e3, 1e-9);
    /* 2 km from the lowest level (35 m) to the highest over NZ levels: the voxel centres at the
     * levels' heights. */
    assert_float_equal(fv.grid.spacing[2], 2e3 / (NZ - 1), 1e-3);
    assert_float_equal(fv.grid.origin[2] + 0.5 * fv.grid.spacing[2], 35.0, 1e-3);
    assert_float_equal(fv.grid.origin[2] + (NZ - 0.5) * fv.grid.spacing[2], 2035.0, 1e-3);
    assert_float_equal(fv.grid.origin[0], 0.0, 0.0);
    assert_non_null(fv.q[SPECIES_CLOUD]);
    assert_non_null(fv.q[SPECIES_SNOW]);
    assert_null(fv.q[SPECIES_RAIN]);
    assert_null(fv.rho_air);
    assert_true(st.present[SPECIES_CLOUD] && !st.present[SPECIES_ICE]);
    assert_int_equal(st.land, 1);
    assert_int_equal(st.negative, 1);
    assert_int_equal(st.nan, 1);
    assert_true(fv.q[SPECIES_CLOUD][0] == 0.0f);
    assert_true(fv.q[SPECIES_CLOUD][1] == 0.0f);
    assert_true(fv.q[SPECIES_CLOUD][2] == 0.0f);
    /* Big-endian decoded exactly; x fastest. */
    assert_true(fv.q[SPECIES_CLOUD][3] == 1e-5f * 3.0f + 2e-3f);
    assert_true(fv.q[SPECIES_SNOW][grid3_index(&fv.grid, 1, 2, 3)] ==
                2e-6f * (float)(N - (1 + NX * (2 + NY * 3))));
    field_volume_finish(&fv);

    /* A step with no bricks. */
    unsigned errors = log_error_count();
    assert_false(isabel_read_step(&d, 2, &fv, NULL));
    assert_int_equal(log_error_count(), errors + 1);
    assert_null(fv.q[SPECIES_CLOUD]);
}

static void test_errors(void **state)
{
    const char *dir = make_dir("short");
    float v[N] = {0};
    write_brick(dir, "QRAIN", 1, v, N - 1);
    struct isabel_desc d = {.dir = dir, .n = {NX, NY, NZ}, .extent_m = {1, 1, 1}};
    struct field_volume fv;
    unsigned errors = log_error_count();
    assert_false(isabel_read_step(&d, 0, &fv, NULL));
    assert_int_equal(log_error_count(), errors + 1);
    assert_non_null(strstr(log_last_error(), "QRAINf01.bin"));
    assert_non_null(strstr(log_last_error(), "data.isabel_size"));

    /* A folder where a brick should be. */
    char path[1024];
    snprintf(path, sizeof(path), "%s/QCLOUDf01.bin", dir);
    mkdir(path, 0755);
    assert_false(isabel_read_step(&d, 0, &fv, NULL));

    struct isabel_desc none = {.dir = test_tmp_path("nothing-here")};
    assert_int_equal(isabel_step_count(&none), 0);
    assert_false(isabel_read_step(&none, 0, &fv, NULL));
}

/* Every brick: the five species, QVAPOR, TC (Celsius) into temperature, U, V, W into wind
 * speed; CLOUD, PRECIP and P described for info. */
static void test_every_brick(void **state)
{
    const char *dir = make_dir("every");
    float v[N];
    for (int f = 0; f < ISABEL_FIELD_COUNT; f++) {
        for (int i = 0; i < N; i++)
            v[i] = (float)(f + 1) * 1e-4f + 1e-6f * (float)i;
        if (!strcmp(isabel_fields[f], "TC"))
            for (int i = 0; i < N; i++)
                v[i] = 25.0f - 0.5f * (float)(i / (NX * NY)); /* falls with height */
        if (!strcmp(isabel_fields[f], "U") || !strcmp(isabel_fields[f], "V") ||
            !strcmp(isabel_fields[f], "W"))
            for (int i = 0; i < N; i++)
                v[i] = isabel_fields[f][0] == 'U' ? 3.0f : isabel_fields[f][0] == 'V' ? -4.0f
                                                                                      : 12.0f;
        if (!strcmp(isabel_fields[f], "P"))
            for (int i = 0; i < N; i++)
                v[i] = -500.0f + (float)i;
        v[7] = ISABEL_LAND;
        write_brick(dir, isabel_fields[f], 1, v, N);
    }
    struct isabel_desc d = {.dir = dir, .n = {NX, NY, NZ}, .extent_m = {60e3, 50e3, 2e3},
                            .qvapor = true, .temperature = true, .wind = true};
    struct field_volume fv;
    assert_true(isabel_read_step(&d, 0, &fv, NULL));
    for (int f = 0; f < SPECIES_COUNT; f++) {
        assert_non_null(fv.q[f]);
        assert_float_equal(fv.q[f][3], (f + 1) * 1e-4 + 3e-6, 1e-9);
    }
    assert_non_null(fv.qvapor);
    assert_float_equal(fv.qvapor[3], 6e-4 + 3e-6, 1e-9);
    assert_non_null(fv.temperature);
    assert_float_equal(fv.temperature[grid3_index(&fv.grid, 1, 1, 2)], 25.0 - 1.0 + 273.15,
                       1e-4);
    /* A land point's temperature is the standard atmosphere's at its height. */
    double t, p;
    wrf_std_atmosphere(ISABEL_BOTTOM_M, &t, &p);
    assert_float_equal(fv.temperature[7], t, 1e-3);
    assert_non_null(fv.wind);
    assert_float_equal(fv.wind[3], 13.0, 1e-5); /* |(3, -4, 12)| */
    assert_float_equal(fv.wind[7], 0.0, 1e-9);  /* land */
    assert_null(fv.u); /* the components only when asked for */
    field_volume_finish(&fv);

    /* Asked for: U, V, W kept beside the speed, land zero in each, and counted in the budget
     * (four arrays for the wind rather than three). */
    struct isabel_desc comp = d;
    comp.wind_components = true;
    assert_true(isabel_read_step(&comp, 0, &fv, NULL));
    assert_non_null(fv.u);
    assert_non_null(fv.v);
    assert_non_null(fv.w);
    assert_float_equal(fv.u[3], 3.0, 1e-6);
    assert_float_equal(fv.v[3], -4.0, 1e-6);
    assert_float_equal(fv.w[3], 12.0, 1e-6);
    assert_float_equal(fv.u[7], 0.0, 1e-9);
    assert_float_equal(fv.wind[3], 13.0, 1e-5);
    struct probe_sample ps;
    double at[3] = {3.5 * fv.grid.spacing[0], 0.5 * fv.grid.spacing[1],
                    fv.grid.origin[2] + 0.5 * fv.grid.spacing[2]};
    assert_true(probe_sample_fields(&fv, at, &ps));
    assert_true(ps.has_wind && ps.has_w);
    double speed, from;
    probe_wind(ps.u, ps.v, &speed, &from);
    assert_float_equal(speed, 5.0, 1e-5);
    assert_float_equal(from, 323.130, 1e-3); /* from the north-west: atan2(-3, 4) */
    assert_float_equal(ps.w, 12.0, 1e-5);
    field_volume_finish(&fv);
    double per_array = (double)N * sizeof(float) / 1048576.0;
    comp.memory_mb = per_array * (SPECIES_COUNT + 2 + 3 + 0.5);
    assert_false(isabel_read_step(&comp, 0, &fv, NULL));
    comp.wind_components = false;
    assert_true(isabel_read_step(&comp, 0, &fv, NULL));
    field_volume_finish(&fv);

    /* The budget: refused before reading, naming data.memory. */
    struct isabel_desc tight = d;
    tight.memory_mb = 1e-4;
    unsigned errors = log_error_count();
    assert_false(isabel_read_step(&tight, 0, &fv, NULL));
    assert_int_equal(log_error_count(), errors + 1);
    assert_non_null(strstr(log_last_error(), "data.memory"));
    assert_null(fv.q[0]);
    tight.memory_mb = 1.0;
    assert_true(isabel_read_step(&tight, 0, &fv, NULL));
    field_volume_finish(&fv);

    /* Without the flags only the species are read. */
    struct isabel_desc plain = d;
    plain.qvapor = plain.temperature = plain.wind = false;
    assert_true(isabel_read_step(&plain, 0, &fv, NULL));
    assert_null(fv.qvapor);
    assert_null(fv.temperature);
    assert_null(fv.wind);
    field_volume_finish(&fv);

    /* info's description of each brick. */
    for (int f = 0; f < ISABEL_FIELD_COUNT; f++) {
        struct isabel_brick_stats st;
        assert_true(isabel_brick_stats(&d, isabel_fields[f], 0, &st));
        assert_true(st.present);
        assert_int_equal(st.land, 1);
    }
    struct isabel_brick_stats st;
    assert_true(isabel_brick_stats(&d, "P", 0, &st));
    assert_float_equal(st.min, -500.0, 1e-9);
    assert_float_equal(st.max, -500.0 + N - 1, 1e-9);
    assert_true(isabel_brick_stats(&d, "QCLOUD", 1, &st));
    assert_false(st.present);

    /* Through the data source: temperature and wind when the look asks for them. */
    const char *files[1] = {dir};
    struct data_source_desc sd;
    memset(&sd, 0, sizeof(sd));
    sd.format = DATA_SOURCE_ISABEL;
    sd.files = files;
    sd.file_count = 1;
    sd.isabel = plain;
    wrf_desc_defaults(&sd.wrf);
    struct data_source *src = data_source_open(&sd);
    assert_non_null(src);
    assert_true(data_source_load_fields_extra(src, 0, true, true, &fv));
    assert_non_null(fv.temperature);
    assert_non_null(fv.wind);
    field_volume_finish(&fv);
    assert_true(data_source_load_fields(src, 0, &fv));
    assert_null(fv.temperature);
    field_volume_finish(&fv);

    /* The georeference: the published box, with no map block. */
    struct geo_map g;
    assert_true(data_source_geo(src, &g));
    assert_int_equal(g.kind, GEO_GRID);
    double lat, lon;
    assert_true(geo_map_to_latlon(&g, 0.5 * 60e3 / NX, 0.5 * 50e3 / NY, &lat,
                                  &lon));
    assert_float_equal(lat, ISABEL_LAT_SOUTH, 1e-4);
    assert_float_equal(lon, ISABEL_LON_WEST, 1e-4);
    assert_true(geo_map_to_latlon(&g, 60e3 - 0.5 * 60e3 / NX, 50e3 - 0.5 * 50e3 / NY, &lat,
                                  &lon));
    assert_float_equal(lat, ISABEL_LAT_NORTH, 1e-4);
    assert_float_equal(lon, ISABEL_LON_EAST, 1e-4);
    geo_map_finish(&g);
    data_source_close(src);
}

/* The full-size grid: the published box at the corners' columns, and the centre. */
static void test_geo_default(void **state)
{
    struct isabel_desc d = {.dir = "."};
    struct geo_map g;
    assert_true(isabel_geo(&d, &g));
    assert_int_equal(g.nx, 500);
    double lat, lon;
    assert_true(geo_map_to_latlon(&g, 2000e3 / 500 * 0.5, 2000e3 / 500 * 0.5, &lat, &lon));
    assert_float_equal(lat, 23.7, 1e-4);
    assert_float_equal(lon, -83.0, 1e-4);
    assert_true(geo_map_to_latlon(&g, 1000e3, 1000e3, &lat, &lon));
    assert_float_equal(lat, 0.5 * (23.7 + 41.7), 0.02);
    assert_float_equal(lon, 0.5 * (-83.0 - 62.0), 0.03);
    double x, y;
    assert_true(geo_map_to_frame(&g, 41.7, -62.0, &x, &y));
    assert_float_equal(x, 2000e3 - 2e3, 1.0);
    assert_float_equal(y, 2000e3 - 2e3, 1.0);
    geo_map_finish(&g);
}

/* The contest's published heights (0.035 km to 19.835 km on 100 levels): the default grid's
 * voxel centres lie on them, 200 m apart. */
static void test_heights_default(void **state)
{
    struct isabel_desc d = {.dir = "."};
    struct grid3 g;
    isabel_grid(&d, &g);
    assert_int_equal(g.n[2], 100);
    assert_float_equal(g.spacing[2], 200.0, 1e-9);
    assert_float_equal(g.origin[2] + 0.5 * g.spacing[2], 35.0, 1e-3);
    assert_float_equal(g.origin[2] + 99.5 * g.spacing[2], 19835.0, 1e-2);
    assert_float_equal(g.spacing[0], 4e3, 1e-9);
    /* One level: a layer of the extent's thickness around the published lowest height. */
    d.n[2] = 1;
    d.extent_m[2] = 500.0;
    isabel_grid(&d, &g);
    assert_float_equal(g.spacing[2], 500.0, 1e-9);
    assert_float_equal(g.origin[2], 35.0 - 250.0, 1e-3);
}

int main(void)
{
    log_set_level(LOG_ERROR);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_read),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_every_brick),
        cmocka_unit_test(test_geo_default),
        cmocka_unit_test(test_heights_default),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
