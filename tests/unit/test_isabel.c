/* Isabel bricks: big-endian floats, land value, missing species, size mismatch. */
#include "testutil.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "common/log.h"
#include "data/isabel.h"

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
    assert_float_equal(fv.grid.spacing[2], 500.0, 1e-9);
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

int main(void)
{
    log_set_level(LOG_ERROR);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_read),
        cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
