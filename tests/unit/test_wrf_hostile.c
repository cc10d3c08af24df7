/* WRF reader: files found by fuzzing and fault injection — cut short (before and after they
 * were opened), headers with one byte changed, budgets, implausible grids and times, series
 * that do not agree.  Each is refused with one message naming the file, never read as zeros. */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <netcdf.h>

#include "common/log.h"
#include "data/synth.h"
#include "data/wrf.h"
#include "data/wrf_write.h"

/* A small storm as anvil synth writes it (64-bit offset format): STEPS steps of NX x NY x NZ,
 * every 10 minutes from 2000-01-01 00:00 + START minutes. */
static void write_synth(const char *path, int nx, int ny, int nz, int steps, int start)
{
    struct synth_desc sd = {.kind = SYNTH_STORM,
                            .n = {nx, ny, nz},
                            .extent_m = {1500.0 * nx, 1500.0 * ny, 16000.0},
                            .seed = 3};
    struct wrf_write_desc wd = {.cen_lat = 25.0, .cen_lon = -89.0};
    struct wrf_writer *ww = NULL;
    for (int s = 0; s < steps; s++) {
        struct field_volume fv;
        sd.time = steps > 1 ? (double)s / (steps - 1) : 0.0;
        assert_true(synth_storm_fields(&sd, &fv));
        if (!ww) {
            ww = wrf_writer_create(path, &fv.grid, &wd);
            assert_non_null(ww);
        }
        char date[32];
        int m = start + 10 * s;
        snprintf(date, sizeof(date), "2000-01-01_%02d:%02d:00", m / 60, m % 60);
        assert_true(wrf_writer_add(ww, &fv, date));
        field_volume_finish(&fv);
    }
    assert_true(wrf_writer_finish(ww));
}

static unsigned char *slurp(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    *len = (size_t)ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *b = malloc(*len);
    assert_int_equal(fread(b, 1, *len, f), *len);
    fclose(f);
    return b;
}

static void spit(const char *path, const void *b, size_t len)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(b, 1, len, f), len);
    fclose(f);
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* Opens PATH and reads every step: true only when all of it reads. */
static bool read_all(const char *path)
{
    struct wrf *w = wrf_open(&path, 1, 0.0);
    if (!w)
        return false;
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    bool ok = true;
    for (int s = 0; s < wrf_step_count(w) && ok; s++) {
        struct field_volume v;
        ok = wrf_read_step(w, s, &d, &v, NULL);
        field_volume_finish(&v);
    }
    wrf_close(w);
    return ok;
}

/* PATH fails (opening or reading) with errors, the last naming PATH and WORD. */
static void expect_refused(const char *path, const char *word)
{
    unsigned errors = log_error_count();
    double t0 = now_s();
    assert_false(read_all(path));
    assert_true(now_s() - t0 < 2.0);
    assert_true(log_error_count() > errors);
    if (!strstr(log_last_error(), path) || (word && !strstr(log_last_error(), word))) {
        fprintf(stderr, "message \"%s\" lacks \"%s\" or \"%s\"\n", log_last_error(), path,
                word ? word : "");
        fail();
    }
}

static void test_cut_short_before_open(void **state)
{
    char good[512], cut[512];
    snprintf(good, sizeof(good), "%s", test_tmp_path("good.nc"));
    snprintf(cut, sizeof(cut), "%s", test_tmp_path("cut.nc"));
    write_synth(good, 6, 5, 4, 3, 0);
    assert_true(read_all(good));
    size_t len;
    unsigned char *b = slurp(good, &len);
    /* Short by one value of the last variable of the last record: it read as zero. */
    const size_t keeps[] = {len - 4, len / 2, len / 10, 100};
    for (int i = 0; i < 4; i++) {
        spit(cut, b, keeps[i]);
        expect_refused(cut, "truncated");
    }
    free(b);
}

static void test_cut_short_while_open(void **state)
{
    char path[512];
    snprintf(path, sizeof(path), "%s", test_tmp_path("open.nc"));
    write_synth(path, 6, 5, 4, 3, 0);
    const char *p = path;
    struct wrf *w = wrf_open(&p, 1, 0.0);
    assert_non_null(w);
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    struct field_volume v;
    assert_true(wrf_read_step(w, 0, &d, &v, NULL));
    field_volume_finish(&v);
    /* The file loses its last record while the series is open. */
    struct stat st;
    assert_int_equal(stat(path, &st), 0);
    assert_int_equal(truncate(path, st.st_size - 100), 0);
    unsigned errors = log_error_count();
    assert_false(wrf_read_step(w, 2, &d, &v, NULL));
    assert_int_equal(log_error_count(), errors + 1);
    assert_non_null(strstr(log_last_error(), path));
    assert_non_null(strstr(log_last_error(), "cut short"));
    assert_null(v.q[SPECIES_CLOUD]);
    wrf_close(w);
}

/* The offset of the 4-byte length after dimension NAME's padded name in B. */
static size_t dim_length_at(const unsigned char *b, size_t len, const char *name)
{
    size_t n = strlen(name), padded = (n + 3) & ~(size_t)3;
    for (size_t i = 4; i + padded + 4 <= len; i++) {
        if (b[i - 1] == n && memcmp(b + i, name, n) == 0 && b[i + n] == 0)
            return i + padded;
    }
    fail_msg("no dimension %s", name);
    return 0;
}

static void test_one_byte_changed(void **state)
{
    char good[512], bad[512];
    snprintf(good, sizeof(good), "%s", test_tmp_path("small.nc"));
    snprintf(bad, sizeof(bad), "%s", test_tmp_path("bad.nc"));
    write_synth(good, 4, 4, 2, 2, 0);
    size_t len;
    unsigned char *b = slurp(good, &len);
    /* 16.5 million records in a 10 KB file (netcdf-c took 21 s over it). */
    unsigned char *c = malloc(len);
    memcpy(c, b, len);
    c[4] = 0x00, c[5] = 0xfb, c[6] = 0xc5, c[7] = 0x20;
    spit(bad, c, len);
    expect_refused(bad, "16500000 records");
    /* west_east = 4 becomes 16 777 220 (netcdf-c took a minute and gigabytes). */
    memcpy(c, b, len);
    c[dim_length_at(c, len, "west_east")] = 0x01;
    spit(bad, c, len);
    expect_refused(bad, "truncated or damaged");
    free(c);
    free(b);
}

static void test_budget_bounds_opening(void **state)
{
    /* 20000 x 20000 columns declared in a few KB of NetCDF-4, no data written: the metadata
     * alone would take 10 GiB (6.3 GB of it touched before the budget applied to opening). */
    char path[512];
    snprintf(path, sizeof(path), "%s", test_tmp_path("huge.nc"));
    int nc, dt, ds, dx, dy, dz, dzs, v;
    assert_int_equal(nc_create(path, NC_CLOBBER | NC_NETCDF4, &nc), NC_NOERR);
    nc_def_dim(nc, "Time", NC_UNLIMITED, &dt);
    nc_def_dim(nc, "DateStrLen", 19, &ds);
    nc_def_dim(nc, "west_east", 20000, &dx);
    nc_def_dim(nc, "south_north", 20000, &dy);
    nc_def_dim(nc, "bottom_top", 2, &dz);
    nc_def_dim(nc, "bottom_top_stag", 3, &dzs);
    float dxy = 1000.0f;
    nc_put_att_float(nc, NC_GLOBAL, "DX", NC_FLOAT, 1, &dxy);
    nc_put_att_float(nc, NC_GLOBAL, "DY", NC_FLOAT, 1, &dxy);
    int d3[3] = {dt, dy, dx}, d4[4] = {dt, dz, dy, dx}, d4s[4] = {dt, dzs, dy, dx};
    int dtimes[2] = {dt, ds};
    nc_def_var(nc, "Times", NC_CHAR, 2, dtimes, &v);
    const char *meta[3] = {"XLAT", "XLONG", "HGT"}, *mass[3] = {"P", "PB", "T"};
    for (int i = 0; i < 3; i++) {
        nc_def_var(nc, meta[i], NC_FLOAT, 3, d3, &v);
        nc_def_var(nc, mass[i], NC_FLOAT, 4, d4, &v);
    }
    nc_def_var(nc, "PH", NC_FLOAT, 4, d4s, &v);
    nc_def_var(nc, "PHB", NC_FLOAT, 4, d4s, &v);
    nc_enddef(nc);
    size_t start[2] = {0, 0}, count[2] = {1, 19};
    int vt;
    nc_inq_varid(nc, "Times", &vt);
    assert_int_equal(nc_put_vara_text(nc, vt, start, count, "2000-01-01_00:00:00"), NC_NOERR);
    assert_int_equal(nc_close(nc), NC_NOERR);
    struct stat st;
    assert_int_equal(stat(path, &st), 0);
    assert_true(st.st_size < 100000);

    unsigned errors = log_error_count();
    double t0 = now_s();
    const char *p = path;
    assert_null(wrf_open(&p, 1, 4096.0));
    assert_true(now_s() - t0 < 1.0);
    assert_int_equal(log_error_count(), errors + 1);
    assert_non_null(strstr(log_last_error(), path));
    assert_non_null(strstr(log_last_error(), "data.memory = 4096 MiB"));
}

/* Sets the global attribute NAME of PATH to V. */
static void set_global(const char *path, const char *name, double v)
{
    int nc;
    assert_int_equal(nc_open(path, NC_WRITE, &nc), NC_NOERR);
    assert_int_equal(nc_redef(nc), NC_NOERR);
    assert_int_equal(nc_put_att_double(nc, NC_GLOBAL, name, NC_FLOAT, 1, &v), NC_NOERR);
    assert_int_equal(nc_close(nc), NC_NOERR);
}

static void expect_open_refused(const char *const *paths, int n, const char *word)
{
    unsigned errors = log_error_count();
    assert_null(wrf_open(paths, n, 0.0));
    assert_int_equal(log_error_count(), errors + 1);
    if (!strstr(log_last_error(), paths[n - 1]) || !strstr(log_last_error(), word)) {
        fprintf(stderr, "message \"%s\" lacks \"%s\"\n", log_last_error(), word);
        fail();
    }
}

static void test_implausible_spacing(void **state)
{
    char path[512];
    snprintf(path, sizeof(path), "%s", test_tmp_path("dx.nc"));
    write_synth(path, 4, 4, 3, 1, 0);
    const char *p = path;
    /* DX = 1e-30 m was accepted (a 188 M-vertex mesh, a minute of work, exit 0). */
    set_global(path, "DX", 1e-30);
    expect_open_refused(&p, 1, "DX = 1e-30 m");
    set_global(path, "DX", 1500.0);
    set_global(path, "DY", 1e9);
    expect_open_refused(&p, 1, "expected a grid spacing from 0.1 m to 1000 km");
    set_global(path, "DY", 1500.0);
    struct wrf *w = wrf_open(&p, 1, 0.0);
    assert_non_null(w);
    wrf_close(w);
}

static void test_series_spacing_differs(void **state)
{
    /* Two files of one grid, one with a different DX: not one series (the first DX was
     * taken for both). */
    char a[512], b[512];
    snprintf(a, sizeof(a), "%s", test_tmp_path("s0.nc"));
    snprintf(b, sizeof(b), "%s", test_tmp_path("s1.nc"));
    write_synth(a, 4, 4, 3, 1, 0);
    write_synth(b, 4, 4, 3, 1, 10);
    set_global(b, "DX", 3000.0);
    const char *paths[2] = {a, b};
    expect_open_refused(paths, 2, "differs from");
    assert_non_null(strstr(log_last_error(), a));
}

/* Variable NAME of PATH (a float variable) times K plus ADD, everywhere. */
static void scale_var(const char *path, const char *name, float k, float add)
{
    int nc, v, ndims, dims[NC_MAX_VAR_DIMS];
    assert_int_equal(nc_open(path, NC_WRITE, &nc), NC_NOERR);
    assert_int_equal(nc_inq_varid(nc, name, &v), NC_NOERR);
    assert_int_equal(nc_inq_varndims(nc, v, &ndims), NC_NOERR);
    assert_int_equal(nc_inq_vardimid(nc, v, dims), NC_NOERR);
    size_t n = 1;
    for (int i = 0; i < ndims; i++) {
        size_t len;
        nc_inq_dimlen(nc, dims[i], &len);
        n *= len;
    }
    float *buf = malloc(n * sizeof(float));
    assert_int_equal(nc_get_var_float(nc, v, buf), NC_NOERR);
    for (size_t i = 0; i < n; i++)
        buf[i] = buf[i] * k + add;
    assert_int_equal(nc_put_var_float(nc, v, buf), NC_NOERR);
    free(buf);
    assert_int_equal(nc_close(nc), NC_NOERR);
}

static void test_implausible_heights(void **state)
{
    /* Geopotential a thousand times too large: heights of thousands of km. */
    char path[512];
    snprintf(path, sizeof(path), "%s", test_tmp_path("z.nc"));
    write_synth(path, 4, 4, 3, 2, 0);
    scale_var(path, "PHB", 1000.0f, 0.0f);
    scale_var(path, "PH", 1000.0f, 0.0f);
    expect_refused(path, "a model top at");
    assert_non_null(strstr(log_last_error(), "expected -1000 m to 100 km above sea level"));
    /* Every level 5 km lower: a plausible top, a ground 4 km below the Dead Sea. */
    write_synth(path, 4, 4, 3, 2, 0);
    scale_var(path, "PH", 1.0f, -5000.0f * 9.81f);
    expect_refused(path, "a height of -5000 m in column (0, 0), level 0");
    /* One column whose third staggered level lies at -500 m: its second mass level is below
     * its first.  Named by its column, on a grid wide enough to be checked by several
     * threads' shares, the first such column only. */
    write_synth(path, 100, 100, 3, 2, 0);
    int nc, ph, phb;
    assert_int_equal(nc_open(path, NC_WRITE, &nc), NC_NOERR);
    assert_int_equal(nc_inq_varid(nc, "PH", &ph), NC_NOERR);
    assert_int_equal(nc_inq_varid(nc, "PHB", &phb), NC_NOERR);
    const size_t at[2][2] = {{41, 77}, {45, 30}}; /* (x, y): a column in the second half, and
                                                      the first in the file's order */
    for (int c = 0; c < 2; c++) {
        size_t idx[4] = {0, 2, at[c][1], at[c][0]};
        float base;
        assert_int_equal(nc_get_var1_float(nc, phb, idx, &base), NC_NOERR);
        float v = -500.0f * 9.81f - base;
        assert_int_equal(nc_put_var1_float(nc, ph, idx, &v), NC_NOERR);
    }
    assert_int_equal(nc_close(nc), NC_NOERR);
    expect_refused(path, "heights do not increase upward in column (45, 30)");
}

static void test_implausible_times(void **state)
{
    char path[512];
    snprintf(path, sizeof(path), "%s", test_tmp_path("t.nc"));
    write_synth(path, 4, 4, 3, 2, 0);
    int nc, v;
    assert_int_equal(nc_open(path, NC_WRITE, &nc), NC_NOERR);
    assert_int_equal(nc_inq_varid(nc, "Times", &v), NC_NOERR);
    size_t start[2] = {1, 0}, count[2] = {1, 19};
    assert_int_equal(nc_put_vara_text(nc, v, start, count, "2000-13-45_99:\377\001:00"), NC_NOERR);
    assert_int_equal(nc_close(nc), NC_NOERR);
    const char *p = path;
    expect_open_refused(&p, 1, "time 1: \"2000-13-45_99:\\xff\\x01:00\" is not a date");
}

static void test_series_with_a_gap(void **state)
{
    /* Five files ten minutes apart matched by a glob, the fourth gone: the series opens, and
     * one warning says which step is missing. */
    char dir[512], pattern[600];
    snprintf(dir, sizeof(dir), "%s/gap", test_tmpdir());
    assert_int_equal(mkdir(dir, 0700), 0);
    for (int i = 0; i < 5; i++) {
        char path[600];
        snprintf(path, sizeof(path), "%s/wrfout_%d.nc", dir, i);
        write_synth(path, 4, 4, 3, 1, 10 * i);
        if (i == 3)
            assert_int_equal(unlink(path), 0);
    }
    snprintf(pattern, sizeof(pattern), "%s/wrfout_*.nc", dir);
    const char *p = pattern;
    unsigned warns = log_warn_count();
    struct wrf *w = wrf_open(&p, 1, 0.0);
    assert_non_null(w);
    assert_int_equal(wrf_step_count(w), 4);
    assert_int_equal(log_warn_count(), warns + 1);
    wrf_close(w);
    /* Evenly spaced: no warning. */
    snprintf(pattern, sizeof(pattern), "%s/wrfout_[012].nc", dir);
    w = wrf_open(&p, 1, 0.0);
    assert_non_null(w);
    assert_int_equal(log_warn_count(), warns + 1);
    wrf_close(w);
}

int main(void)
{
    log_set_level(LOG_NONE);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cut_short_before_open), cmocka_unit_test(test_cut_short_while_open),
        cmocka_unit_test(test_one_byte_changed),      cmocka_unit_test(test_budget_bounds_opening),
        cmocka_unit_test(test_implausible_spacing),   cmocka_unit_test(test_series_spacing_differs),
        cmocka_unit_test(test_implausible_heights),   cmocka_unit_test(test_implausible_times),
        cmocka_unit_test(test_series_with_a_gap),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
