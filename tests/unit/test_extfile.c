/* Extinction files: write, read back exactly, CF attributes, failures leave old files. */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <netcdf.h>

#include "app/cmd_data.h"
#include "common/log.h"
#include "data/extfile.h"

static void make_volume(struct ext_volume *v, int step)
{
    struct grid3 g = {
        .n = {5, 4, 3}, .spacing = {2000.0, 1500.0, 250.0}, .origin = {1000.0, -3000.0, 0.0}};
    assert_true(ext_volume_init(v, &g));
    size_t n = grid3_count(&g);
    for (size_t i = 0; i < n; i++) {
        v->beta[2 * i] = 1e-4f * (float)(i + 1) + (float)step;
        v->beta[2 * i + 1] = 3e-3f * (float)(n - i) + 0.5f * (float)step;
    }
}

static char *att_text(int nc, int var, const char *name)
{
    size_t len = 0;
    if (nc_inq_attlen(nc, var, name, &len) != NC_NOERR)
        return NULL;
    char *s = calloc(len + 1, 1);
    nc_get_att_text(nc, var, name, s);
    return s;
}

static void test_round_trip(void **state)
{
    char path[512];
    snprintf(path, sizeof(path), "%s", test_tmp_path("ext.nc"));
    struct ext_volume v[3];
    for (int s = 0; s < 3; s++)
        make_volume(&v[s], s);
    struct extfile_writer *w =
        extfile_writer_create(path, &v[0].grid, "storm.nc", "anvil convert storm.nc -o ext.nc",
                              "cloud rain ice snow graupel, scale 1");
    assert_non_null(w);
    assert_true(extfile_writer_add(w, &v[0], "2005-08-28_12:00:00"));
    assert_true(extfile_writer_add(w, &v[1], "2005-08-28_15:00:00"));
    assert_true(extfile_writer_add(w, &v[2], "2005-08-29_00:00:00"));
    assert_true(extfile_writer_finish(w));

    /* CF layout, read with the NetCDF API directly. */
    int nc, var;
    assert_int_equal(nc_open(path, NC_NOWRITE, &nc), NC_NOERR);
    char *s = att_text(nc, NC_GLOBAL, "Conventions");
    assert_string_equal(s, "CF-1.8");
    free(s);
    s = att_text(nc, NC_GLOBAL, "source");
    assert_string_equal(s, "storm.nc");
    free(s);
    assert_non_null(s = att_text(nc, NC_GLOBAL, "history"));
    free(s);
    assert_int_equal(nc_inq_varid(nc, "beta_ice", &var), NC_NOERR);
    s = att_text(nc, var, "units");
    assert_string_equal(s, "m-1");
    free(s);
    assert_int_equal(nc_inq_varid(nc, "x", &var), NC_NOERR);
    s = att_text(nc, var, "units");
    assert_string_equal(s, "m");
    free(s);
    double x[5];
    assert_int_equal(nc_get_var_double(nc, var, x), NC_NOERR);
    assert_float_equal(x[0], 2000.0, 1e-9); /* centre of the first cell */
    assert_float_equal(x[4], 10000.0, 1e-9);
    assert_int_equal(nc_inq_varid(nc, "time", &var), NC_NOERR);
    s = att_text(nc, var, "units");
    assert_string_equal(s, "seconds since 2005-08-28 12:00:00");
    free(s);
    double t[3];
    assert_int_equal(nc_get_var_double(nc, var, t), NC_NOERR);
    assert_float_equal(t[0], 0.0, 0.0);
    assert_float_equal(t[1], 3 * 3600.0, 0.0);
    assert_float_equal(t[2], 12 * 3600.0, 0.0);
    nc_close(nc);

    /* Our reader: same grid, same values, bit for bit. */
    struct extfile *f = extfile_open(path, 0.0);
    assert_non_null(f);
    assert_int_equal(extfile_step_count(f), 3);
    assert_string_equal(extfile_step_date(f, 1), "2005-08-28_15:00:00");
    const struct grid3 *g = extfile_grid(f);
    for (int a = 0; a < 3; a++) {
        assert_int_equal(g->n[a], v[0].grid.n[a]);
        assert_float_equal(g->spacing[a], v[0].grid.spacing[a], 1e-9);
        assert_float_equal(g->origin[a], v[0].grid.origin[a], 1e-9);
    }
    for (int step = 2; step >= 0; step--) {
        struct ext_volume r;
        struct extfile_stats st;
        assert_true(extfile_read_step(f, step, &r, &st));
        assert_int_equal(st.nan + st.inf + st.fill + st.negative, 0);
        assert_memory_equal(r.beta, v[step].beta, grid3_count(g) * 2 * sizeof(float));
        ext_volume_finish(&r);
    }
    struct ext_volume r;
    assert_false(extfile_read_step(f, 3, &r, NULL));
    extfile_close(f);
    for (int i = 0; i < 3; i++)
        ext_volume_finish(&v[i]);
}

static void test_failed_write_keeps_old_file(void **state)
{
    char path[512];
    snprintf(path, sizeof(path), "%s", test_tmp_path("keep.nc"));
    struct ext_volume a, b;
    make_volume(&a, 0);
    struct grid3 other = {.n = {2, 2, 2}, .spacing = {1, 1, 1}};
    assert_true(ext_volume_init(&b, &other));
    struct extfile_writer *w = extfile_writer_create(path, &a.grid, "", "", NULL);
    assert_true(extfile_writer_add(w, &a, ""));
    assert_true(extfile_writer_finish(w));

    /* A second write that fails (a step on another grid) leaves the first file as it was. */
    w = extfile_writer_create(path, &a.grid, "", "", NULL);
    assert_non_null(w);
    unsigned errors = log_error_count();
    assert_false(extfile_writer_add(w, &b, ""));
    assert_int_equal(log_error_count(), errors + 1);
    assert_false(extfile_writer_finish(w));
    struct extfile *f = extfile_open(path, 0.0);
    assert_non_null(f);
    assert_int_equal(extfile_step_count(f), 1);
    assert_string_equal(extfile_step_date(f, 0), "");
    struct ext_volume r;
    assert_true(extfile_read_step(f, 0, &r, NULL));
    assert_memory_equal(r.beta, a.beta, grid3_count(&a.grid) * 2 * sizeof(float));
    ext_volume_finish(&r);
    extfile_close(f);

    /* A folder that does not exist. */
    assert_null(extfile_writer_create(test_tmp_path("no/such/dir/x.nc"), &a.grid, "", "", NULL));
    extfile_writer_destroy(NULL);
    ext_volume_finish(&a);
    ext_volume_finish(&b);
}

static void test_bad_values_and_layout(void **state)
{
    char path[512];
    snprintf(path, sizeof(path), "%s", test_tmp_path("bad.nc"));
    struct ext_volume a;
    make_volume(&a, 0);
    a.beta[0] = NAN;
    a.beta[3] = -1.0f;
    a.beta[5] = INFINITY;
    a.beta[7] = NC_FILL_FLOAT;
    struct extfile_writer *w = extfile_writer_create(path, &a.grid, "", "", NULL);
    assert_true(extfile_writer_add(w, &a, "2020-02-29_23:59:59"));
    assert_true(extfile_writer_finish(w));
    struct extfile *f = extfile_open(path, 0.0);
    struct ext_volume r;
    struct extfile_stats st;
    assert_true(extfile_read_step(f, 0, &r, &st));
    assert_int_equal(st.nan, 1);
    assert_int_equal(st.negative, 1);
    assert_int_equal(st.inf, 1);
    assert_int_equal(st.fill, 1);
    assert_true(r.beta[0] == 0.0f && r.beta[3] == 0.0f && r.beta[5] == 0.0f && r.beta[7] == 0.0f);
    assert_true(r.beta[1] == a.beta[1]);
    ext_volume_finish(&r);
    extfile_close(f);
    ext_volume_finish(&a);

    /* Not an extinction file: a WRF sample, a text file. */
    unsigned errors = log_error_count();
    assert_null(extfile_open(test_shared_data("wrf/katrina_2005_mercator_wsm3.nc"), 0.0));
    assert_null(extfile_open(test_write_file("t.nc", "hello"), 0.0));
    assert_int_equal(log_error_count(), errors + 2);

    /* A file missing beta_water. */
    int nc, dt, dz, dy, dx, v;
    char p2[512];
    snprintf(p2, sizeof(p2), "%s", test_tmp_path("half.nc"));
    assert_int_equal(nc_create(p2, NC_CLOBBER, &nc), NC_NOERR);
    nc_def_dim(nc, "time", NC_UNLIMITED, &dt);
    nc_def_dim(nc, "z", 2, &dz);
    nc_def_dim(nc, "y", 2, &dy);
    nc_def_dim(nc, "x", 2, &dx);
    int d4[4] = {dt, dz, dy, dx};
    nc_def_var(nc, "beta_ice", NC_FLOAT, 4, d4, &v);
    nc_close(nc);
    assert_null(extfile_open(p2, 0.0));
}

static void test_dates(void **state)
{
    double s;
    assert_true(extfile_parse_date("1970-01-01_00:00:00", &s));
    assert_float_equal(s, 0.0, 0.0);
    assert_true(extfile_parse_date("2005-08-28_12:00:00", &s));
    assert_float_equal(s, 1125230400.0, 0.0);
    assert_true(extfile_parse_date("2000-03-01 00:00:00", &s));
    assert_float_equal(s, 951868800.0, 0.0);
    assert_false(extfile_parse_date("", &s));
    assert_false(extfile_parse_date("2005-13-28_12:00:00", &s));
}

/* The commands: synth writes a WRF series, convert turns it (and the Katrina sample) into
 * extinction files, info describes both; bad input and usage give exit codes 1 and 2. */
static void test_commands(void **state)
{
    char synth[512], ext[512], kat[512];
    snprintf(synth, sizeof(synth), "%s", test_tmp_path("cmd-synth.nc"));
    snprintf(ext, sizeof(ext), "%s", test_tmp_path("cmd-ext.nc"));
    snprintf(kat, sizeof(kat), "%s", test_tmp_path("cmd-katrina.nc"));
    char *synth_argv[] = {"synth", "-o",       synth,      "--size", "20x16x10", "--steps",
                          "3",     "--extent", "30x24x12", "--seed", "5"};
    assert_int_equal(cmd_synth(11, synth_argv), 0);
    char *convert_argv[] = {"convert", synth, "-o", ext};
    assert_int_equal(cmd_convert(4, convert_argv), 0);
    struct extfile *f = extfile_open(ext, 0.0);
    assert_non_null(f);
    assert_int_equal(extfile_step_count(f), 3);
    assert_string_equal(extfile_step_date(f, 2), "2000-01-01_00:20:00");
    assert_int_equal(extfile_grid(f)->n[0], 20);
    assert_float_equal(extfile_grid(f)->spacing[2], 1200.0, 1e-3);
    struct ext_volume v;
    assert_true(extfile_read_step(f, 1, &v, NULL));
    assert_true(ext_volume_max_beta(&v) > 0.0);
    ext_volume_finish(&v);
    extfile_close(f);

    /* Katrina: cloud and rain only, so the ice-phase volume is empty. */
    char *kat_argv[] = {"convert", (char *)test_shared_data("wrf/katrina_2005_mercator_wsm3.nc"),
                        "-o", kat};
    assert_int_equal(cmd_convert(4, kat_argv), 0);
    f = extfile_open(kat, 0.0);
    assert_non_null(f);
    assert_int_equal(extfile_step_count(f), 4);
    assert_true(extfile_read_step(f, 0, &v, NULL));
    double ice = 0.0, water = 0.0;
    for (size_t i = 0; i < grid3_count(&v.grid); i++) {
        ice = fmax(ice, v.beta[2 * i]);
        water = fmax(water, v.beta[2 * i + 1]);
    }
    assert_float_equal(ice, 0.0, 0.0);
    assert_true(water > 0.01);
    ext_volume_finish(&v);
    extfile_close(f);

    char *info_argv[] = {"info", synth};
    assert_int_equal(cmd_info(2, info_argv), 0);
    char *info_ext[] = {"info", ext};
    assert_int_equal(cmd_info(2, info_ext), 0);
    char *info_bad[] = {"info", (char *)test_write_file("junk.nc", "junk")};
    assert_int_equal(cmd_info(2, info_bad), 1);
    char *info_none[] = {"info"};
    assert_int_equal(cmd_info(1, info_none), 2);
    char *synth_bad[] = {"synth", "-o", synth, "--size", "20x16"};
    assert_int_equal(cmd_synth(5, synth_bad), 1); /* a bad value */
    char *synth_noout[] = {"synth", "--steps", "2"};
    assert_int_equal(cmd_synth(3, synth_noout), 2);
    char *convert_noout[] = {"convert", synth};
    assert_int_equal(cmd_convert(2, convert_noout), 2);
}

int main(void)
{
    log_set_level(LOG_ERROR);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_round_trip),
        cmocka_unit_test(test_failed_write_keeps_old_file),
        cmocka_unit_test(test_bad_values_and_layout),
        cmocka_unit_test(test_dates),
        cmocka_unit_test(test_commands),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
