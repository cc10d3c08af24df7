/* data/ncopen: the classic-format header check against files netcdf-c writes, cut and
 * damaged. */
#include "testutil.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <netcdf.h>

#include "common/log.h"
#include "data/ncopen.h"

#define CHECK(x) assert_int_equal((x), NC_NOERR)

static unsigned char *slurp(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    *len = (size_t)ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *b = malloc(*len ? *len : 1);
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

/* A file in CMODE with fixed and record variables of every classic type, attributes of every
 * type, and RECS records; ONE_RECORD_VAR: a single short record variable (the unpadded
 * case). */
static const char *make_file(const char *name, int cmode, int recs, bool one_record_var)
{
    static char path[512];
    snprintf(path, sizeof(path), "%s", test_tmp_path(name));
    int nc, dt, dx, dy;
    CHECK(nc_create(path, NC_CLOBBER | cmode, &nc));
    CHECK(nc_def_dim(nc, "time", NC_UNLIMITED, &dt));
    CHECK(nc_def_dim(nc, "x", 3, &dx));
    CHECK(nc_def_dim(nc, "y", 5, &dy));
    signed char b[3] = {1, 2, 3};
    short sh[3] = {4, 5, 6};
    int in[3] = {7, 8, 9};
    float fl[3] = {1.5f, 2.5f, 3.5f};
    double db[3] = {0.25, 0.5, 0.75};
    CHECK(nc_put_att_text(nc, NC_GLOBAL, "title", 5, "hello"));
    CHECK(nc_put_att_schar(nc, NC_GLOBAL, "b", NC_BYTE, 3, b));
    CHECK(nc_put_att_short(nc, NC_GLOBAL, "s", NC_SHORT, 3, sh));
    CHECK(nc_put_att_int(nc, NC_GLOBAL, "i", NC_INT, 3, in));
    CHECK(nc_put_att_float(nc, NC_GLOBAL, "f", NC_FLOAT, 3, fl));
    CHECK(nc_put_att_double(nc, NC_GLOBAL, "d", NC_DOUBLE, 3, db));
    int shape[2] = {dt, dx}, grid[2] = {dy, dx};
    int vr, vs, vc, vf, vd;
    CHECK(nc_def_var(nc, "rec_short", NC_SHORT, 2, shape, &vr));
    CHECK(nc_put_att_text(nc, vr, "units", 1, "m"));
    if (!one_record_var) {
        CHECK(nc_def_var(nc, "rec_char", NC_CHAR, 2, shape, &vc));
        CHECK(nc_def_var(nc, "rec_double", NC_DOUBLE, 2, shape, &vd));
    }
    CHECK(nc_def_var(nc, "fixed_byte", NC_BYTE, 2, grid, &vs));
    CHECK(nc_def_var(nc, "fixed_float", NC_FLOAT, 1, &dx, &vf));
    CHECK(nc_enddef(nc));
    signed char g[15] = {0};
    CHECK(nc_put_var_schar(nc, vs, g));
    CHECK(nc_put_var_float(nc, vf, fl));
    for (size_t t = 0; t < (size_t)recs; t++) {
        size_t start[2] = {t, 0}, count[2] = {1, 3};
        CHECK(nc_put_vara_short(nc, vr, start, count, sh));
        if (!one_record_var) {
            CHECK(nc_put_vara_text(nc, vc, start, count, "abc"));
            CHECK(nc_put_vara_double(nc, vd, start, count, db));
        }
    }
    CHECK(nc_close(nc));
    return path;
}

struct kind {
    const char *name;
    int cmode;
};

static const struct kind kinds[] = {
    {"cdf1.nc", 0},
    {"cdf2.nc", NC_64BIT_OFFSET},
    {"cdf5.nc", NC_64BIT_DATA},
};

static void test_files_netcdf_writes_pass(void **state)
{
    char why[512];
    for (int k = 0; k < 3; k++) {
        for (int one = 0; one < 2; one++) {
            for (int recs = 0; recs <= 3; recs += 3) {
                size_t len;
                unsigned char *b = slurp(make_file(kinds[k].name, kinds[k].cmode, recs, one), &len);
                uint64_t need = 0;
                if (!data_nc_check_classic(b, len, why, sizeof(why), &need)) {
                    fprintf(stderr, "%s (%d records): %s\n", kinds[k].name, recs, why);
                    fail();
                }
                /* netcdf-c pads the file to whole records; our need may stop short of the
                 * last record's padding, never more than 7 bytes. */
                assert_true(need <= len);
                assert_true(need + 8 > len);
                free(b);
            }
        }
    }
}

static void test_every_cut_is_refused(void **state)
{
    /* Every length short of what the header needs is refused, with a reason; nothing is read
     * past the buffer (the unit tests run under AddressSanitizer). */
    char why[512];
    for (int k = 0; k < 3; k++) {
        for (int one = 0; one < 2; one++) {
            size_t len;
            unsigned char *b = slurp(make_file(kinds[k].name, kinds[k].cmode, 3, one), &len);
            uint64_t need = 0;
            assert_true(data_nc_check_classic(b, len, why, sizeof(why), &need));
            for (size_t cut = 0; cut < need; cut++) {
                unsigned char *copy = malloc(cut ? cut : 1);
                memcpy(copy, b, cut);
                why[0] = '\0';
                if (data_nc_check_classic(copy, cut, why, sizeof(why), NULL)) {
                    fprintf(stderr, "%s cut to %zu of %llu bytes passed\n", kinds[k].name, cut,
                            (unsigned long long)need);
                    fail();
                }
                assert_true(why[0] != '\0');
                free(copy);
            }
            free(b);
        }
    }
}

/* The offset of the 4-byte big-endian length that follows NAME's padded name in B. */
static size_t after_name(const unsigned char *b, size_t len, const char *name)
{
    size_t n = strlen(name), padded = (n + 3) & ~(size_t)3;
    for (size_t i = 0; i + padded + 4 <= len; i++) {
        if (memcmp(b + i, name, n) == 0 && b[i + n] == 0)
            return i + padded;
    }
    fail_msg("no %s in the header", name);
    return 0;
}

static void put32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)(v >> 24);
    p[1] = (unsigned char)(v >> 16);
    p[2] = (unsigned char)(v >> 8);
    p[3] = (unsigned char)v;
}

static void expect_refused(const unsigned char *b, size_t len, const char *word)
{
    char why[512] = "";
    assert_false(data_nc_check_classic(b, len, why, sizeof(why), NULL));
    if (!strstr(why, word)) {
        fprintf(stderr, "reason \"%s\" lacks \"%s\"\n", why, word);
        fail();
    }
}

static void test_damaged_headers(void **state)
{
    size_t len;
    unsigned char *good = slurp(make_file("dmg.nc", NC_64BIT_OFFSET, 3, false), &len);
    unsigned char *b = malloc(len);

    /* A record count of 16.5 million (netcdf-c spends seconds and gigabytes on it). */
    memcpy(b, good, len);
    put32(b + 4, 16500000);
    expect_refused(b, len, "16500000 records need the file to reach byte");
    /* One byte of a dimension's length. */
    memcpy(b, good, len);
    b[after_name(b, len, "y")] = 0x40;
    expect_refused(b, len, "fixed_byte");
    /* A list of 2^31 - 1 dimensions, attributes, variables. */
    memcpy(b, good, len);
    put32(b + 12, INT32_MAX);
    expect_refused(b, len, "entries (at most");
    /* A name's length past the end of the file, a negative length. */
    memcpy(b, good, len);
    put32(b + 16, 1u << 30);
    expect_refused(b, len, "a name of 1073741824 bytes");
    memcpy(b, good, len);
    put32(b + after_name(b, len, "x"), 0x80000003u);
    expect_refused(b, len, "negative");
    /* An attribute whose values run past the file. */
    memcpy(b, good, len);
    size_t at = after_name(b, len, "title");
    put32(b + at + 4, 0x7fffff00u);
    expect_refused(b, len, "run past the end of the file");
    /* An unknown type. */
    memcpy(b, good, len);
    put32(b + at, 77);
    expect_refused(b, len, "unknown type 77");
    /* Not classic at all. */
    memcpy(b, good, len);
    b[3] = 3;
    expect_refused(b, len, "not a classic NetCDF file");
    free(b);
    free(good);
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

static void test_open(void **state)
{
    char why[512];
    int nc;
    struct data_nc_layout l;
    /* A good file of each format opens, and says what it is. */
    char path[512];
    snprintf(path, sizeof(path), "%s", make_file("open.nc", NC_64BIT_OFFSET, 2, false));
    assert_true(data_nc_open(path, &nc, &l, why, sizeof(why)));
    assert_int_equal(l.format, DATA_NC_64BIT_OFFSET);
    assert_true(l.need > 0 && l.need <= l.file_size);
    nc_close(nc);
    char nc4[512];
    snprintf(nc4, sizeof(nc4), "%s", make_file("open4.nc", NC_NETCDF4, 2, false));
    assert_true(data_nc_open(nc4, &nc, &l, why, sizeof(why)));
    assert_int_equal(l.format, DATA_NC_HDF5);
    nc_close(nc);

    /* Cut short: refused before nc_open, quickly, naming the format. */
    size_t len;
    unsigned char *b = slurp(path, &len);
    const char *cut = test_tmp_path("cut.nc");
    char cutp[512];
    snprintf(cutp, sizeof(cutp), "%s", cut);
    spit(cutp, b, len - 40);
    double t0 = now_s();
    assert_false(data_nc_open(cutp, &nc, &l, why, sizeof(why)));
    assert_true(now_s() - t0 < 1.0);
    assert_int_equal(nc, -1);
    assert_non_null(strstr(why, "64-bit offset NetCDF header"));
    assert_non_null(strstr(why, "truncated"));

    /* Not NetCDF, a FIFO, a folder, a URL. */
    assert_false(
        data_nc_open(test_write_file("text.nc", "hello, world\n"), &nc, &l, why, sizeof(why)));
    assert_non_null(strstr(why, "not a NetCDF file"));
    char fifo[512];
    snprintf(fifo, sizeof(fifo), "%s", test_tmp_path("fifo.nc"));
    assert_int_equal(mkfifo(fifo, 0600), 0);
    assert_false(data_nc_open(fifo, &nc, &l, why, sizeof(why)));
    assert_non_null(strstr(why, "FIFO"));
    assert_false(data_nc_open(test_tmpdir(), &nc, &l, why, sizeof(why)));
    assert_false(data_nc_open("https://example.invalid/x.nc", &nc, &l, why, sizeof(why)));

    /* Cut after it was opened: data_nc_still_whole says so. */
    spit(cutp, b, len);
    assert_true(data_nc_open(cutp, &nc, &l, why, sizeof(why)));
    assert_true(data_nc_still_whole(cutp, &l));
    assert_int_equal(truncate(cutp, (off_t)(len / 2)), 0);
    unsigned errors = log_error_count();
    assert_false(data_nc_still_whole(cutp, &l));
    assert_int_equal(log_error_count(), errors + 1);
    assert_non_null(strstr(log_last_error(), cutp));
    assert_non_null(strstr(log_last_error(), "cut short"));
    nc_close(nc);
    free(b);
}

int main(void)
{
    log_set_level(LOG_NONE);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_files_netcdf_writes_pass),
        cmocka_unit_test(test_every_cut_is_refused),
        cmocka_unit_test(test_damaged_headers),
        cmocka_unit_test(test_open),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
