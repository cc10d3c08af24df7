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

int main(void)
{
    log_set_level(LOG_NONE);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cut_short_before_open),
        cmocka_unit_test(test_cut_short_while_open),
        cmocka_unit_test(test_one_byte_changed),
        cmocka_unit_test(test_budget_bounds_opening),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
