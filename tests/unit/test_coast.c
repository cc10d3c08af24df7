/* data/coast: GSHHG binned files, good and hostile (indices and counts near INT_MAX). */
#include "testutil.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <netcdf.h>

#include "common/log.h"
#include "data/coast.h"

#define CHECK(x) assert_int_equal((x), NC_NOERR)

/* What one file holds: a layout of BINS_X x BINS_Y bins of BIN_MINUTES (N_BINS claimed), one
 * segment in bin 0 that starts at point P0 and has NPTS points, and N_POINTS points. */
struct binned_desc {
    int bin_minutes, bins_x, bins_y, n_bins;
    int seg_bin_first, seg_bin_count; /* bin 0's first segment and segment count */
    int p0, npts, n_points;
};

static void put_scalar(int nc, int dim, const char *name, int value)
{
    int v;
    CHECK(nc_redef(nc));
    CHECK(nc_def_var(nc, name, NC_INT, 1, &dim, &v));
    CHECK(nc_enddef(nc));
    CHECK(nc_put_var_int(nc, v, &value));
}

static const char *make_binned(const char *name, const struct binned_desc *d)
{
    static char path[512];
    snprintf(path, sizeof(path), "%s", test_tmp_path(name));
    int nc, ds, db, dseg, dp;
    CHECK(nc_create(path, NC_CLOBBER, &nc));
    CHECK(nc_def_dim(nc, "Dimension_of_scalar", 1, &ds));
    CHECK(nc_def_dim(nc, "Dimension_of_bin_arrays", (size_t)d->n_bins, &db));
    CHECK(nc_def_dim(nc, "Dimension_of_segment_arrays", 1, &dseg));
    CHECK(nc_def_dim(nc, "Dimension_of_point_arrays", (size_t)d->n_points, &dp));
    int vfirst, vnseg, vinfo, vp0, vlon, vlat;
    CHECK(nc_def_var(nc, "Id_of_first_segment_in_a_bin", NC_INT, 1, &db, &vfirst));
    CHECK(nc_def_var(nc, "N_segments_in_a_bin", NC_SHORT, 1, &db, &vnseg));
    CHECK(
        nc_def_var(nc, "Embedded_npts_levels_exit_entry_for_a_segment", NC_INT, 1, &dseg, &vinfo));
    CHECK(nc_def_var(nc, "Id_of_first_point_in_a_segment", NC_INT, 1, &dseg, &vp0));
    CHECK(nc_def_var(nc, "Relative_longitude_from_SW_corner_of_bin", NC_SHORT, 1, &dp, &vlon));
    CHECK(nc_def_var(nc, "Relative_latitude_from_SW_corner_of_bin", NC_SHORT, 1, &dp, &vlat));
    CHECK(nc_enddef(nc));
    put_scalar(nc, ds, "Bin_size_in_minutes", d->bin_minutes);
    put_scalar(nc, ds, "N_bins_in_360_longitude_range", d->bins_x);
    put_scalar(nc, ds, "N_bins_in_180_degree_latitude_range", d->bins_y);
    put_scalar(nc, ds, "N_bins_in_file", d->n_bins);
    put_scalar(nc, ds, "N_segments_in_file", 1);
    put_scalar(nc, ds, "N_points_in_file", d->n_points);
    size_t one = 1, zero = 0;
    CHECK(nc_put_var1_int(nc, vfirst, &zero, &d->seg_bin_first));
    short ns = (short)d->seg_bin_count;
    CHECK(nc_put_var1_short(nc, vnseg, &zero, &ns));
    /* npts in bits 9 and up, level 1 (land) in bits 6 to 8 */
    int info = (int)((unsigned)d->npts << 9 | 1u << 6);
    CHECK(nc_put_vara_int(nc, vinfo, &zero, &one, &info));
    CHECK(nc_put_vara_int(nc, vp0, &zero, &one, &d->p0));
    /* Points along the bin's diagonal: (i / n) of the bin from its south-west corner. */
    for (size_t i = 0; i < (size_t)d->n_points; i++) {
        unsigned short f = (unsigned short)(65535u * i / (size_t)(d->n_points - 1));
        short s;
        memcpy(&s, &f, sizeof(s));
        CHECK(nc_put_var1_short(nc, vlon, &i, &s));
        CHECK(nc_put_var1_short(nc, vlat, &i, &s));
    }
    CHECK(nc_close(nc));
    return path;
}

/* 2 x 1 bins of 180 degrees: bin 0 covers longitudes 0..180, latitudes -90..90. */
static const struct binned_desc good = {.bin_minutes = 10800,
                                        .bins_x = 2,
                                        .bins_y = 1,
                                        .n_bins = 2,
                                        .seg_bin_first = 0,
                                        .seg_bin_count = 1,
                                        .p0 = 0,
                                        .npts = 5,
                                        .n_points = 5};

static const double whole_bin[4] = {-90.0, 90.0, 0.0, 180.0};

static void test_good_file(void **state)
{
    const char *path = make_binned("good.nc", &good);
    struct coast_lines c;
    assert_true(coast_read(path, whole_bin, COAST_LAND, &c));
    assert_int_equal(c.n_lines, 1);
    assert_int_equal(c.count[0], 5);
    assert_int_equal(c.level[0], COAST_LAND);
    /* Point i at floor(65535 i / 4) / 65535 of the bin (180 degrees) from its corner. */
    for (int i = 0; i < 5; i++) {
        double f = (double)(65535u * (unsigned)i / 4u) / 65535.0;
        assert_float_equal(c.lat[i], -90.0 + 180.0 * f, 1e-9);
        assert_float_equal(c.lon[i], 180.0 * f, 1e-9);
    }
    coast_lines_finish(&c);
}

static void test_point_range_near_int_max(void **state)
{
    /* First point INT_MAX - 1 with 4 points: p0 + npts is past INT_MAX (signed overflow), and
     * a check in int let the reader index 2^31 points beyond the arrays. */
    struct binned_desc d = good;
    d.p0 = INT_MAX - 1;
    d.npts = 4;
    const char *path = make_binned("p0.nc", &d);
    struct coast_lines c;
    assert_true(coast_read(path, whole_bin, COAST_LAND, &c));
    assert_int_equal(c.n_lines, 0);
    coast_lines_finish(&c);
    /* A segment longer than the points there are. */
    d.p0 = 3;
    d.npts = (1 << 23) - 1;
    path = make_binned("npts.nc", &d);
    assert_true(coast_read(path, whole_bin, COAST_LAND, &c));
    assert_int_equal(c.n_lines, 0);
    coast_lines_finish(&c);
}

static void test_segment_range_near_int_max(void **state)
{
    /* A bin whose segments start at INT_MAX - 1: s0 + ns is past INT_MAX. */
    struct binned_desc d = good;
    d.seg_bin_first = INT_MAX - 1;
    d.seg_bin_count = 5;
    const char *path = make_binned("s0.nc", &d);
    struct coast_lines c;
    assert_true(coast_read(path, whole_bin, COAST_LAND, &c));
    assert_int_equal(c.n_lines, 0);
    coast_lines_finish(&c);
}

static void test_bin_layout_overflow(void **state)
{
    /* 21600 x 198842 bins of 1' is 4 294 987 200, which wraps to 19 904 in int: the file
     * claims that many, and a product in int agreed.  Refused (one warning: coastlines are
     * optional). */
    struct binned_desc d = good;
    d.bin_minutes = 1;
    d.bins_x = 21600;
    d.bins_y = 198842;
    d.n_bins = 19904;
    const char *path = make_binned("bins.nc", &d);
    struct coast_lines c;
    unsigned warns = log_warn_count();
    log_set_level(LOG_NONE);
    assert_false(coast_read(path, whole_bin, COAST_LAND, &c));
    log_set_level(LOG_INFO);
    assert_int_equal(log_warn_count(), warns + 1);
    /* Latitude bins that do not cover 180 degrees are as wrong. */
    d = good;
    d.bins_y = 3;
    d.n_bins = 6;
    path = make_binned("lat.nc", &d);
    log_set_level(LOG_NONE);
    assert_false(coast_read(path, whole_bin, COAST_LAND, &c));
    log_set_level(LOG_INFO);
    assert_int_equal(log_warn_count(), warns + 2);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_good_file),
        cmocka_unit_test(test_point_range_near_int_max),
        cmocka_unit_test(test_segment_range_near_int_max),
        cmocka_unit_test(test_bin_layout_overflow),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
