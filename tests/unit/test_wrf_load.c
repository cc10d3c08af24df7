/* The load path against values computed here from the file read with netcdf-c: every mass
 * ratio voxel equals the column resampled alone (wrf_resample_column) from the file's values
 * and heights, bit for bit; air density within float rounding of the double-precision formula
 * resampled the same way; extinction equal to Nes eq. 5.3 summed per phase.  On the Katrina
 * and Lambert samples and on a synthetic file read onto other levels, with a crop and a
 * stride.  And QVAPOR is read only when asked; a step read in slabs of any size, and straight to
 * extinction, gives the same numbers, and scanned (anvil info) the same counts. */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <netcdf.h>

#include "data/derived.h"
#include "data/source.h"
#include "data/synth.h"
#include "data/volume.h"
#include "data/wrf.h"
#include "optics/optics.h"
#include "optics/transfer.h"

#define CHECK(x) assert_int_equal((x), NC_NOERR)

/* A variable of time TIME over the selection's columns on LEVELS levels (levels slowest). */
static float *read_nc(int nc, const char *name, int time, int levels, int x0, int sx, int nx,
                      int y0, int sy, int ny)
{
    int varid;
    CHECK(nc_inq_varid(nc, name, &varid));
    float *buf = malloc((size_t)levels * nx * ny * sizeof(float));
    assert_non_null(buf);
    size_t start[4] = {(size_t)time, 0, (size_t)y0, (size_t)x0};
    size_t count[4] = {1, (size_t)levels, (size_t)ny, (size_t)nx};
    ptrdiff_t stride[4] = {1, 1, sy, sx};
    CHECK(nc_get_vars_float(nc, varid, start, count, stride, buf));
    return buf;
}

/* Float ulps between A and B (both finite). */
static double ulps(float a, float b)
{
    float m = fmaxf(fabsf(a), fabsf(b));
    if (m == 0.0f)
        return 0.0;
    return fabs((double)a - (double)b) / (nextafterf(m, INFINITY) - m);
}

/* Reads step STEP of PATH with D and checks it voxel by voxel against the file. */
static void check_step(const char *path, int step, const struct wrf_desc *d)
{
    struct wrf *w = wrf_open(&path, 1, 0.0);
    assert_non_null(w);
    const struct wrf_meta *m = wrf_get_meta(w);
    struct field_volume out;
    assert_true(wrf_read_step(w, step, d, &out, NULL));
    const struct grid3 *g = &out.grid;

    int x0 = d->crop[0] > 0 ? d->crop[0] : 0, y0 = d->crop[2] > 0 ? d->crop[2] : 0;
    int sx = d->stride[0] > 1 ? d->stride[0] : 1, sy = d->stride[1] > 1 ? d->stride[1] : 1;
    int nx = g->n[0], ny = g->n[1], nz = m->nz, no = g->n[2];
    size_t cols = (size_t)nx * ny;
    int nc;
    CHECK(nc_open(path, NC_NOWRITE, &nc));
    float *ph = read_nc(nc, "PH", step, nz + 1, x0, sx, nx, y0, sy, ny);
    float *phb = read_nc(nc, "PHB", step, nz + 1, x0, sx, nx, y0, sy, ny);
    float *p = read_nc(nc, "P", step, nz, x0, sx, nx, y0, sy, ny);
    float *pb = read_nc(nc, "PB", step, nz, x0, sx, nx, y0, sy, ny);
    float *t = read_nc(nc, "T", step, nz, x0, sx, nx, y0, sy, ny);
    float *q[SPECIES_COUNT] = {NULL};
    for (int f = 0; f < SPECIES_COUNT; f++) {
        assert_true((out.q[f] != NULL) == m->has_species[f]);
        if (m->has_species[f])
            q[f] = read_nc(nc, species_wrf_name((enum species)f), step, nz, x0, sx, nx, y0, sy,
                           ny);
    }
    CHECK(nc_close(nc));

    double *z = malloc((size_t)nz * sizeof(double));
    float *col = malloc((size_t)nz * sizeof(float));
    float *res = malloc((size_t)no * sizeof(float));
    assert_true(z && col && res);
    double dz = g->spacing[2], z0 = g->origin[2];
    size_t compared = 0, interpolated = 0;
    double worst_rho = 0.0;
    for (size_t c = 0; c < cols; c++) {
        /* Heights as docs/data.md says: (PH + PHB) / g on staggered levels, mass levels half
         * way. */
        float zw0 = (float)(((double)ph[c] + phb[c]) / WRF_G);
        float zwt = (float)(((double)ph[(size_t)nz * cols + c] + phb[(size_t)nz * cols + c]) /
                            WRF_G);
        for (int k = 0; k < nz; k++) {
            size_t a = (size_t)k * cols + c, b = a + cols;
            float za = (float)(((double)ph[a] + phb[a]) / WRF_G);
            float zb = (float)(((double)ph[b] + phb[b]) / WRF_G);
            z[k] = 0.5 * ((double)za + (double)zb);
        }
        for (int f = 0; f < SPECIES_COUNT; f++) {
            if (!q[f])
                continue;
            for (int k = 0; k < nz; k++) {
                float v = q[f][(size_t)k * cols + c];
                col[k] = isfinite(v) && v >= 0.0f && v <= 1.0f ? v : 0.0f;
            }
            wrf_resample_column(z, col, nz, zw0, zwt, z0, dz, no, 0.0f, res, NULL);
            for (int o = 0; o < no; o++) {
                float got = out.q[f][cols * (size_t)o + c];
                if (got != res[o])
                    fail_msg("%s: %s column %zu level %d: %.9g, resampled alone %.9g", path,
                             species_wrf_name((enum species)f), c, o, got, res[o]);
                compared++;
                interpolated += res[o] != 0.0f && res[o] != col[0];
            }
        }
        for (int k = 0; k < nz; k++) {
            size_t a = (size_t)k * cols + c;
            double rho = optics_wrf_air_density((double)(p[a] + pb[a]), (double)t[a] + WRF_T0);
            col[k] = rho > 0.0 ? (float)rho : NAN;
        }
        wrf_resample_column(z, col, nz, zw0, zwt, z0, dz, no, NAN, res, NULL);
        for (int o = 0; o < no; o++) {
            float want = isfinite(res[o]) ? res[o]
                                          : (float)optics_std_atmosphere_density(
                                                z0 + (o + 0.5) * dz);
            double u = ulps(out.rho_air[cols * (size_t)o + c], want);
            worst_rho = u > worst_rho ? u : worst_rho;
        }
    }
    /* Nes eq. 5.3 per voxel, summed per phase in species order. */
    struct optics_params op;
    optics_params_defaults(&op);
    struct ext_volume ext;
    assert_true(ext_volume_from_fields(&out, &op, NULL, &ext));
    for (size_t i = 0; i < grid3_count(g); i++) {
        double sum[2] = {0.0, 0.0};
        for (int f = 0; f < SPECIES_COUNT; f++) {
            if (out.q[f] && out.q[f][i] > 0.0f)
                sum[species_is_ice((enum species)f) ? 0 : 1] +=
                    3.0 * out.rho_air[i] * out.q[f][i] / (2.0 * op.density[f] * op.radius_m[f]);
        }
        assert_true(ext.beta[2 * i] == (float)sum[0]);
        assert_true(ext.beta[2 * i + 1] == (float)sum[1]);
    }
    print_message("%s step %d: %zu mass ratios equal (%zu between levels), air density within "
                  "%.2f ulps\n",
                  path, step, compared, interpolated, worst_rho);
    assert_true(compared > 0);
    assert_true(interpolated > 0); /* the comparison saw resampling, not copies */
    assert_true(worst_rho <= 2.0);

    ext_volume_finish(&ext);
    free(z);
    free(col);
    free(res);
    free(ph);
    free(phb);
    free(p);
    free(pb);
    free(t);
    for (int f = 0; f < SPECIES_COUNT; f++)
        free(q[f]);
    field_volume_finish(&out);
    wrf_close(w);
}

static void test_katrina(void **state)
{
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    check_step(test_shared_data("wrf/katrina_2005_mercator_wsm3.nc"), 2, &d);
    d.levels = 40; /* finer than the model's 14 levels */
    d.stride[0] = 2;
    d.stride[1] = 3;
    d.crop[0] = 5;
    d.crop[2] = 7;
    check_step(test_shared_data("wrf/katrina_2005_mercator_wsm3.nc"), 1, &d);
}

static void test_lambert(void **state)
{
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    check_step(test_shared_data("wrf/lambert_thompson_cropped.nc"), 3, &d);
    d.levels = 11;
    check_step(test_shared_data("wrf/lambert_thompson_cropped.nc"), 0, &d);
}

/* The procedural storm on N mass points over EXTENT metres (SEED) as a one-step WRF file. */
static void write_storm_step(const char *path, const int n[3], const double extent[3], int seed)
{
    struct synth_desc sd = {.kind = SYNTH_STORM, .seed = (unsigned)seed};
    memcpy(sd.n, n, sizeof(sd.n));
    memcpy(sd.extent_m, extent, sizeof(sd.extent_m));
    struct field_volume in;
    assert_true(synth_storm_fields(&sd, &in));
    test_write_wrf_step(path, &in);
    field_volume_finish(&in);
}

static void test_synth(void **state)
{
    char path[512];
    snprintf(path, sizeof(path), "%s", test_tmp_path("synth.nc"));
    write_storm_step(path, (const int[3]){40, 30, 24}, (const double[3]){80000.0, 60000.0, 15000.0},
                     5);
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    d.levels = 37; /* not the file's 24: every output between two levels */
    check_step(path, 0, &d);
    d.stride[0] = 3;
    d.crop[2] = 4;
    d.crop[3] = 25;
    check_step(path, 0, &d);
}

/* QVAPOR, and the wind's components with the vorticity, are read when a load asks for them,
 * not otherwise. */
static void test_qvapor_when_asked(void **state)
{
    const char *files[] = {test_shared_data("wrf/katrina_2005_mercator_wsm3.nc")};
    struct data_source_desc sd = {.format = DATA_SOURCE_WRF, .files = files, .file_count = 1};
    wrf_desc_defaults(&sd.wrf);
    optics_params_defaults(&sd.optics);
    species_select_defaults(&sd.select);
    struct data_source *s = data_source_open(&sd);
    assert_non_null(s);
    assert_true(wrf_get_meta(data_source_wrf(s))->has_qvapor);
    struct field_volume v;
    assert_true(data_source_load_fields_want(s, 0, &(struct data_fields_want){0}, &v));
    assert_null(v.qvapor);
    assert_null(v.temperature);
    assert_null(v.u);
    assert_null(v.vorticity);
    assert_non_null(v.q[SPECIES_CLOUD]);
    field_volume_finish(&v);
    assert_true(data_source_load_fields_want(
        s, 0, &(struct data_fields_want){.wind_components = true}, &v));
    assert_non_null(v.u);
    assert_non_null(v.v);
    assert_non_null(v.w);
    assert_non_null(v.vorticity);
    assert_non_null(v.wind);
    /* A hurricane: somewhere near the ground, cyclonic vorticity well above f (1e-4 1/s). */
    float zmax = 0.0f;
    for (size_t i = 0; i < grid3_count(&v.grid); i++) {
        assert_true(isfinite(v.vorticity[i]) && isfinite(v.w[i]));
        zmax = fmaxf(zmax, v.vorticity[i]);
    }
    assert_true(zmax > 1e-3f);
    field_volume_finish(&v);
    assert_true(data_source_load_fields_want(s, 0, &(struct data_fields_want){.qvapor = true}, &v));
    assert_non_null(v.qvapor);
    assert_null(v.temperature);
    field_volume_finish(&v);
    data_source_close(s);
}

/* A field volume's arrays equal, bit for bit. */
static void assert_same_array(const float *a, const float *b, size_t n, const char *what)
{
    assert_true((a == NULL) == (b == NULL));
    if (a && memcmp(a, b, n * sizeof(float)) != 0)
        fail_msg("%s differs", what);
}

static void assert_same_fields(const struct field_volume *a, const struct field_volume *b)
{
    assert_memory_equal(a->grid.n, b->grid.n, sizeof(a->grid.n));
    size_t n = grid3_count(&a->grid);
    for (int f = 0; f < SPECIES_COUNT; f++)
        assert_same_array(a->q[f], b->q[f], n, species_wrf_name((enum species)f));
    assert_same_array(a->qvapor, b->qvapor, n, "QVAPOR");
    assert_same_array(a->rho_air, b->rho_air, n, "air density");
    assert_same_array(a->temperature, b->temperature, n, "temperature");
    assert_same_array(a->wind, b->wind, n, "wind");
    assert_same_array(a->vorticity, b->vorticity, n, "vorticity");
    assert_int_equal(a->level_count, b->level_count);
    assert_same_array(a->level_z, b->level_z,
                      (size_t)a->grid.n[0] * a->grid.n[1] * (size_t)a->level_count, "levels");
}

static void assert_same_stats(const struct wrf_stats *a, const struct wrf_stats *b)
{
    assert_int_equal(a->below_terrain, b->below_terrain);
    assert_int_equal(a->above_top, b->above_top);
    for (int v = 0; v < WRF_VAR_COUNT; v++) {
        const struct wrf_var_stats *x = &a->var[v], *y = &b->var[v];
        assert_int_equal(x->read, y->read);
        assert_int_equal(x->count, y->count);
        assert_int_equal(x->nan, y->nan);
        assert_int_equal(x->inf, y->inf);
        assert_int_equal(x->fill, y->fill);
        assert_int_equal(x->negative, y->negative);
        assert_int_equal(x->absurd, y->absurd);
        assert_true(x->min == y->min && x->max == y->max);
    }
}

/* A step read a slab of ROWS rows at a time gives the numbers and counts of the step read in
 * one slab; straight to extinction (data_source_load) it gives what the fields make through
 * ext_volume_from_fields. */
static void check_slabs(const char *path, int step, const struct wrf_desc *base, int rows)
{
    struct wrf *w = wrf_open(&path, 1, 0.0);
    assert_non_null(w);
    struct wrf_desc d = *base;
    d.slab_rows = 100000; /* the whole step in one slab */
    struct field_volume one, many;
    struct wrf_stats st_one, st_many;
    assert_true(wrf_read_step(w, step, &d, &one, &st_one));
    d.slab_rows = rows;
    assert_true(wrf_read_step(w, step, &d, &many, &st_many));
    assert_same_fields(&one, &many);
    assert_same_stats(&st_one, &st_many);

    struct optics_params op;
    optics_params_defaults(&op);
    struct species_select sel;
    species_select_defaults(&sel);
    for (int look = 0; look < 2; look++) {
        if (look == 1) { /* rain off, snow doubled */
            sel.enabled[SPECIES_RAIN] = false;
            sel.scale[SPECIES_SNOW] = 2.0;
        }
        struct ext_volume whole, slabs;
        assert_true(ext_volume_from_fields(&one, &op, &sel, &whole));
        struct wrf_stats st;
        assert_true(wrf_read_step_ext(w, step, &d, &op, &sel, NULL, &slabs, &st));
        assert_memory_equal(whole.grid.n, slabs.grid.n, sizeof(whole.grid.n));
        assert_true(memcmp(whole.beta, slabs.beta, grid3_count(&whole.grid) * 2 * sizeof(float)) ==
                    0);
        assert_int_equal(st.below_terrain, st_one.below_terrain);
        for (int f = 0; f < SPECIES_COUNT; f++) /* only what extinction uses is read */
            assert_int_equal(st.var[f].read, st_one.var[f].read && sel.enabled[f]);
        assert_false(st.var[WRF_QVAPOR].read);
        ext_volume_finish(&whole);
        ext_volume_finish(&slabs);
    }
    /* The scan (anvil info) checks what the read checks. */
    struct wrf_stats scan;
    assert_true(wrf_scan_step(w, step, &d, &scan));
    scan.below_terrain = st_one.below_terrain;
    scan.above_top = st_one.above_top;
    for (int v = WRF_U; v <= WRF_W; v++) /* the wind is not scanned */
        assert_false(scan.var[v].read);
    memcpy(&scan.var[WRF_U], &st_one.var[WRF_U], 3 * sizeof(scan.var[0]));
    assert_same_stats(&st_one, &scan);
    field_volume_finish(&one);
    field_volume_finish(&many);
    wrf_close(w);
}

/* Straight to extinction with the water vapour's histogram (the transfer editor's default
 * field, which anvil run's menu shows): the bins that the fields' QVAPOR fills through
 * derived_field (HAS: the file has QVAPOR, else both hold the stand-in profile), QVAPOR's
 * checks those of the fields' read, and the extinction the same as without it. */
static void check_vapour(const char *path, int step, const struct wrf_desc *base, int rows,
                         bool has)
{
    struct wrf *w = wrf_open(&path, 1, 0.0);
    assert_non_null(w);
    struct wrf_desc d = *base;
    d.slab_rows = rows;
    d.qvapor = true;
    struct field_volume fv;
    struct wrf_stats st_fields;
    assert_true(wrf_read_step(w, step, &d, &fv, &st_fields));
    assert_true(has == (fv.qvapor != NULL));
    struct transfer_function tf;
    transfer_defaults(&tf, TRANSFER_FIELD_QVAPOR);
    struct transfer_histogram want, got;
    transfer_histogram_init(&want, tf.field, tf.lo, tf.hi);
    size_t n = grid3_count(&fv.grid);
    float *v = malloc(n * sizeof(float));
    assert_non_null(v);
    derived_field(&fv, TRANSFER_FIELD_QVAPOR, v);
    for (size_t i = 0; i < n; i++)
        transfer_histogram_add(&want, v[i]);
    free(v);

    struct optics_params op;
    optics_params_defaults(&op);
    struct species_select sel;
    species_select_defaults(&sel);
    struct ext_volume with, without;
    struct wrf_stats st;
    transfer_histogram_init(&got, tf.field, tf.lo, tf.hi);
    assert_true(wrf_read_step_ext(w, step, &d, &op, &sel, &got, &with, &st));
    assert_true(wrf_read_step_ext(w, step, &d, &op, &sel, NULL, &without, NULL));
    assert_memory_equal(with.grid.n, fv.grid.n, sizeof(fv.grid.n));
    assert_true(memcmp(with.beta, without.beta, n * 2 * sizeof(float)) == 0);
    assert_memory_equal(want.count, got.count, sizeof(want.count));
    assert_int_equal(want.below, got.below);
    assert_int_equal(want.above, got.above);
    assert_int_equal(want.nonfinite, got.nonfinite);
    assert_int_equal(got.total, n);
    int bins = 0;
    for (int i = 0; i < TRANSFER_HISTOGRAM_BINS; i++)
        bins += got.count[i] > 0;
    assert_true(bins >= 2); /* a histogram, not one bar */
    assert_true(st.var[WRF_QVAPOR].read == has);
    const struct wrf_var_stats *a = &st.var[WRF_QVAPOR], *b = &st_fields.var[WRF_QVAPOR];
    assert_int_equal(a->count, has ? b->count : 0);
    assert_int_equal(a->nan + a->inf + a->fill + a->negative + a->absurd,
                     has ? b->nan + b->inf + b->fill + b->negative + b->absurd : 0);
    ext_volume_finish(&with);
    ext_volume_finish(&without);
    field_volume_finish(&fv);
    wrf_close(w);
}

/* A synthetic step written to PATH without QVAPOR (renamed away). */
static void write_without_vapour(const char *path)
{
    write_storm_step(path, (const int[3]){24, 20, 10}, (const double[3]){48000.0, 40000.0, 12000.0},
                     5);
    int nc, varid;
    CHECK(nc_open(path, NC_WRITE, &nc));
    CHECK(nc_redef(nc));
    CHECK(nc_inq_varid(nc, "QVAPOR", &varid));
    CHECK(nc_rename_var(nc, varid, "QVAPOR_OFF"));
    CHECK(nc_close(nc));
}

static void test_vapour_histogram(void **state)
{
    char katrina[512], lambert[512], dry[512];
    snprintf(katrina, sizeof(katrina), "%s", test_shared_data("wrf/katrina_2005_mercator_wsm3.nc"));
    snprintf(lambert, sizeof(lambert), "%s", test_shared_data("wrf/lambert_thompson_cropped.nc"));
    snprintf(dry, sizeof(dry), "%s", test_tmp_path("no_vapour.nc"));
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    check_vapour(katrina, 2, &d, 1, true);
    check_vapour(katrina, 2, &d, 7, true);
    check_vapour(lambert, 1, &d, 3, true);
    d.native_levels = true;
    check_vapour(lambert, 0, &d, 5, true);
    wrf_desc_defaults(&d);
    d.stride[0] = 2;
    d.crop[2] = 5;
    check_vapour(katrina, 1, &d, 2, true);
    write_without_vapour(dry);
    wrf_desc_defaults(&d);
    check_vapour(dry, 0, &d, 3, false);
}

static void test_slabs(void **state)
{
    char katrina[512], lambert[512]; /* test_shared_data's buffer is reused */
    snprintf(katrina, sizeof(katrina), "%s", test_shared_data("wrf/katrina_2005_mercator_wsm3.nc"));
    snprintf(lambert, sizeof(lambert), "%s", test_shared_data("wrf/lambert_thompson_cropped.nc"));
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    check_slabs(katrina, 2, &d, 1);
    check_slabs(lambert, 1, &d, 3);
    /* Everything a field load can make, on other levels, cropped and subsampled. */
    d.qvapor = d.temperature = d.wind_components = d.level_heights = true;
    d.levels = 33;
    d.stride[0] = 2;
    d.stride[1] = 3;
    d.crop[2] = 5;
    check_slabs(katrina, 1, &d, 2);
    wrf_desc_defaults(&d);
    d.native_levels = true;
    check_slabs(lambert, 0, &d, 5);
    d.no_density = true;
    check_slabs(katrina, 0, &d, 4);
}

/* Bad values spread over many slabs are counted and replaced as in one. */
static void test_slabs_bad_values(void **state)
{
    char path[512];
    snprintf(path, sizeof(path), "%s", test_tmp_path("bad.nc"));
    write_storm_step(path, (const int[3]){20, 30, 12}, (const double[3]){40000.0, 60000.0, 12000.0},
                     3);
    int nc, qc, qr, p, qv;
    CHECK(nc_open(path, NC_WRITE, &nc));
    CHECK(nc_inq_varid(nc, "QVAPOR", &qv));
    CHECK(nc_inq_varid(nc, "QCLOUD", &qc));
    CHECK(nc_inq_varid(nc, "QRAIN", &qr));
    CHECK(nc_inq_varid(nc, "P", &p));
    for (int i = 0; i < 40; i++) {
        size_t at[4] = {0, (size_t)(i % 12), (size_t)((i * 7) % 30), (size_t)((i * 3) % 20)};
        float bad[4] = {NAN, -1e-3f, 5.0f, INFINITY};
        CHECK(nc_put_var1_float(nc, i % 2 ? qc : qr, at, &bad[i % 4]));
        float fill = NC_FILL_FLOAT;
        if (i % 5 == 0)
            CHECK(nc_put_var1_float(nc, p, at, &fill));
        if (i % 3 == 0)
            CHECK(nc_put_var1_float(nc, qv, at, &bad[i % 4]));
    }
    CHECK(nc_close(nc));
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    check_slabs(path, 0, &d, 1);
    check_slabs(path, 0, &d, 7);
    check_vapour(path, 0, &d, 1, true);
    check_vapour(path, 0, &d, 7, true);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_katrina),
        cmocka_unit_test(test_lambert),
        cmocka_unit_test(test_synth),
        cmocka_unit_test(test_qvapor_when_asked),
        cmocka_unit_test(test_slabs),
        cmocka_unit_test(test_vapour_histogram),
        cmocka_unit_test(test_slabs_bad_values),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
