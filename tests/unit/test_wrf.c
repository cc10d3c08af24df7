/* WRF reader: the two real samples, the resampling, and malformed files made here. */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <netcdf.h>

#include "common/log.h"
#include "data/synth.h"
#include "data/wrf.h"
#include "data/wrf_write.h"

#define KATRINA "wrf/katrina_2005_mercator_wsm3.nc"
#define LAMBERT "wrf/lambert_thompson_cropped.nc"

static struct wrf *open_one(const char *shared_name)
{
    const char *path = test_shared_data(shared_name);
    return wrf_open(&path, 1, 0.0);
}

/* rho from P + PB and theta as in SPEC.md, with WRF's R_d = 287, c_p = 1004.5. */
static double expected_rho(double p, double pb, double t)
{
    double ptot = p + pb, theta = t + 300.0;
    double tabs = theta * pow(ptot / 100000.0, 287.0 / 1004.5);
    return ptot / (287.0 * tabs);
}

static void test_katrina_meta(void **state)
{
    struct wrf *w = open_one(KATRINA);
    assert_non_null(w);
    const struct wrf_meta *m = wrf_get_meta(w);
    assert_int_equal(m->nx, 48);
    assert_int_equal(m->ny, 48);
    assert_int_equal(m->nz, 14);
    assert_float_equal(m->dx, 10000.0, 1e-9);
    assert_float_equal(m->dy, 10000.0, 1e-9);
    assert_int_equal(m->map_proj, 3);
    assert_int_equal(m->mp_physics, 3);
    /* WSM3: cloud and rain only. */
    assert_true(m->has_species[SPECIES_CLOUD]);
    assert_true(m->has_species[SPECIES_RAIN]);
    assert_false(m->has_species[SPECIES_ICE]);
    assert_false(m->has_species[SPECIES_SNOW]);
    assert_false(m->has_species[SPECIES_GRAUPEL]);
    assert_true(m->has_qvapor);
    assert_int_equal(wrf_step_count(w), 4);
    assert_string_equal(wrf_step_date(w, 0), "2005-08-28_12:00:00");
    assert_string_equal(wrf_step_date(w, 3), "2005-08-28_21:00:00");
    /* Values read with ncdump. */
    assert_non_null(m->xlat);
    assert_float_equal(m->xlat[0], 21.80395, 1e-4);
    assert_float_equal(m->xlong[0], -91.6534, 1e-4);
    assert_float_equal(m->xlat[47 * 48 + 47], 25.67273, 1e-4);
    assert_float_equal(m->xlong[47 * 48 + 47], -87.42593, 1e-4);
    assert_non_null(m->hgt);
    assert_float_equal(m->hgt[24 * 48 + 24], 0.0, 1e-9);
    assert_null(m->landmask); /* the Katrina sample has no LANDMASK */
    assert_true(m->lat_min <= 21.80396 && m->lat_max >= 25.67272);
    wrf_close(w);
}

/* The Katrina sample is a moving nest (it follows the storm north-west): every step has its
 * own XLAT and XLONG (values read with the NetCDF library), the first step's are the meta's;
 * the Lambert sample, one step, does not move. */
static void test_katrina_moves(void **state)
{
    struct wrf *w = open_one(KATRINA);
    assert_non_null(w);
    assert_true(wrf_moves(w));
    const struct wrf_meta *m0 = wrf_step_meta(w, 0), *m3 = wrf_step_meta(w, 3);
    assert_float_equal(m0->xlat[0], 21.80395, 1e-4);
    assert_float_equal(m3->xlat[0], 22.80254, 1e-4);
    assert_float_equal(m3->xlong[0], -93.00261, 1e-4);
    assert_float_equal(m3->xlat[47 * 48 + 47], 26.64153, 1e-4);
    assert_float_equal(m3->xlong[47 * 48 + 47], -88.77514, 1e-4);
    assert_true(m3->lat_max >= 26.6415 && m3->lat_min <= 22.8026);
    assert_float_equal(m0->lat_min, wrf_get_meta(w)->lat_min, 0.0);
    assert_non_null(m3->hgt);
    assert_int_equal(m3->nx, 48);
    assert_float_equal(m3->dx, 10000.0, 1e-9);
    assert_true(wrf_step_meta(w, 7) == wrf_get_meta(w)); /* no such step: the meta's */
    wrf_close(w);
    w = open_one(LAMBERT);
    assert_non_null(w);
    assert_false(wrf_moves(w));
    assert_true(wrf_step_meta(w, 0) == wrf_get_meta(w));
    wrf_close(w);
}

static void test_katrina_step(void **state)
{
    struct wrf *w = open_one(KATRINA);
    assert_non_null(w);
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    d.qvapor = true;
    struct field_volume v;
    struct wrf_stats st;
    assert_true(wrf_read_step(w, 0, &d, &v, &st));
    assert_int_equal(v.grid.n[0], 48);
    assert_int_equal(v.grid.n[1], 48);
    assert_int_equal(v.grid.n[2], 14);
    assert_float_equal(v.grid.spacing[0], 10000.0, 1e-9);
    assert_float_equal(v.grid.origin[2], 0.0, 1e-9);
    /* The sample keeps 15 of the run's 30 staggered levels (BOTTOM-TOP_GRID_DIMENSION says 30):
     * the highest model top, (PH + PHB) / g at the last staggered level, is about 6.15 km. */
    double top = v.grid.n[2] * v.grid.spacing[2];
    assert_true(top > 5700.0 && top < 6500.0);
    assert_non_null(v.q[SPECIES_CLOUD]);
    assert_non_null(v.q[SPECIES_RAIN]);
    assert_null(v.q[SPECIES_ICE]);
    assert_null(v.q[SPECIES_SNOW]);
    assert_null(v.q[SPECIES_GRAUPEL]);
    assert_non_null(v.qvapor);
    assert_non_null(v.rho_air);

    /* Ranges of the raw values (ncdump): QCLOUD max 0.001810972 at time 0; QRAIN has 7
     * negative values at time 0 and max 0.005284014. */
    assert_true(st.var[WRF_QCLOUD].read);
    assert_int_equal(st.var[WRF_QCLOUD].count, 48 * 48 * 14);
    assert_float_equal(st.var[WRF_QCLOUD].max, 0.001810972, 1e-9);
    assert_int_equal(st.var[WRF_QRAIN].negative, 7);
    assert_int_equal(wrf_var_stats_bad(&st.var[WRF_QRAIN]), 7);
    assert_float_equal(st.var[WRF_QRAIN].max, 0.005284014, 1e-9);
    assert_false(st.var[WRF_QICE].read);
    assert_int_equal(st.var[WRF_QCLOUD].nan + st.var[WRF_QCLOUD].fill, 0);

    /* No negative mass ratio survives; resampling does not overshoot. */
    size_t n = grid3_count(&v.grid);
    float qmax = 0.0f;
    for (size_t i = 0; i < n; i++) {
        assert_true(v.q[SPECIES_RAIN][i] >= 0.0f);
        qmax = fmaxf(qmax, v.q[SPECIES_CLOUD][i]);
    }
    assert_true(qmax > 0.0f && qmax <= 0.001810972f * 1.0001f);

    /* Heights increase upward: vapour and air density fall with height, level by level. */
    size_t cols = 48 * 48;
    double prev_q = INFINITY, prev_rho = INFINITY;
    for (int k = 0; k < v.grid.n[2]; k++) {
        double sq = 0.0, sr = 0.0;
        for (size_t c = 0; c < cols; c++) {
            sq += v.qvapor[c + cols * k];
            sr += v.rho_air[c + cols * k];
        }
        assert_true(sq / cols < prev_q);
        assert_true(sr / cols < prev_rho);
        prev_q = sq / cols;
        prev_rho = sr / cols;
    }
    /* Air density near the ground (the lowest level) is physical everywhere. */
    for (size_t c = 0; c < cols; c++)
        assert_true(v.rho_air[c] > 0.5f && v.rho_air[c] < 1.4f);

    /* Every step of the series lands on the same grid (the model top moves with time). */
    for (int s = 1; s < 4; s++) {
        struct field_volume u;
        assert_true(wrf_read_step(w, s, &d, &u, NULL));
        assert_memory_equal(&u.grid, &v.grid, sizeof(v.grid));
        field_volume_finish(&u);
    }
    field_volume_finish(&v);
    wrf_close(w);
}

/* A fine grid whose lowest targets lie between the ground and the first mass level, where the
 * reader clamps to the first level's value: spot values straight from ncdump. */
static void test_katrina_spot_values(void **state)
{
    struct wrf *w = open_one(KATRINA);
    assert_non_null(w);
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    d.qvapor = true;
    d.levels = 1000;
    d.top_m = 10000.0; /* 10 m levels; column (10, 10): ground 0 m, first mass level 30.3 m */
    struct field_volume v;
    assert_true(wrf_read_step(w, 0, &d, &v, NULL));
    double rho = expected_rho(-95.72656, 99667.5, 2.289789);
    for (int k = 0; k < 3; k++) {
        size_t idx = grid3_index(&v.grid, 10, 10, k);
        assert_float_equal(v.qvapor[idx], 0.02160464, 1e-8);
        assert_float_equal(v.rho_air[idx], rho, rho * 2e-3);
    }
    /* Between the first two mass levels (30.3 m and ~91 m) the value is interpolated. */
    size_t idx = grid3_index(&v.grid, 10, 10, 5);
    assert_true(v.qvapor[idx] <= 0.02160464f);
    field_volume_finish(&v);
    wrf_close(w);
}

static void test_lambert(void **state)
{
    struct wrf *w = open_one(LAMBERT);
    assert_non_null(w);
    const struct wrf_meta *m = wrf_get_meta(w);
    assert_int_equal(m->nx, 10);
    assert_int_equal(m->ny, 8);
    assert_int_equal(m->nz, 27);
    assert_float_equal(m->dx, 30000.0, 1e-9);
    assert_int_equal(m->map_proj, 1);
    assert_int_equal(m->mp_physics, 8);
    for (int f = 0; f < SPECIES_COUNT; f++)
        assert_true(m->has_species[f]);
    /* Times(Time, string19); HGT, XLAT without Time. */
    assert_int_equal(wrf_step_count(w), 4);
    assert_string_equal(wrf_step_date(w, 0), "2005-09-21_00:00:00");
    assert_string_equal(wrf_step_date(w, 3), "2005-09-21_09:00:00");
    assert_float_equal(m->hgt[0], 4798.562, 1e-2);
    assert_float_equal(m->hgt[4 * 10 + 5], 5250.023, 1e-2);
    assert_non_null(m->landmask);
    assert_float_equal(m->landmask[0], 1.0, 0.0);
    assert_float_equal(m->xlat[7 * 10 + 9], 30.93666, 1e-4);
    assert_float_equal(m->xlong[7 * 10 + 9], 88.41653, 1e-4);

    /* Column (5, 4): ground 5250.0 m, first mass level 5275.3 m.  Levels of 10 m from 5200 m:
     * five below the ground (zero), then clamped to the first level. */
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    d.qvapor = true;
    d.bottom_m = 5200.0;
    d.top_m = 5300.0;
    d.levels = 10;
    struct field_volume v;
    struct wrf_stats st;
    assert_true(wrf_read_step(w, 0, &d, &v, &st));
    for (int f = 0; f < SPECIES_COUNT; f++)
        assert_non_null(v.q[f]);
    assert_float_equal(st.var[WRF_QSNOW].max, 2.85447e-05, 1e-10);
    assert_float_equal(st.var[WRF_QICE].max, 8.343861e-08, 1e-13);
    assert_float_equal(st.var[WRF_QGRAUP].max, 7.891776e-09, 1e-14);
    assert_true(st.below_terrain > 0);
    double rho = expected_rho(2171.691, 51734.12, 21.78427);
    for (int k = 0; k < 10; k++) {
        size_t idx = grid3_index(&v.grid, 5, 4, k);
        if (k < 5) {
            assert_float_equal(v.qvapor[idx], 0.0, 0.0);
        } else if (k < 8) {
            assert_float_equal(v.qvapor[idx], 0.005008117, 1e-9);
            assert_float_equal(v.rho_air[idx], rho, rho * 2e-3);
        }
    }
    field_volume_finish(&v);

    /* Thermodynamic ranges at time 2 (ncdump): T from 28.28944 to 180.4803 K. */
    wrf_desc_defaults(&d);
    assert_true(wrf_read_step(w, 2, &d, &v, &st));
    assert_float_equal(st.var[WRF_T].min, 28.28944, 1e-4);
    assert_float_equal(st.var[WRF_T].max, 180.4803, 1e-3);
    assert_true(v.grid.origin[2] == 0.0);
    /* Everything below the plateau (HGT > 4 km) is below terrain, so zero. */
    for (int f = 0; f < SPECIES_COUNT; f++)
        assert_float_equal(v.q[f][grid3_index(&v.grid, 5, 4, 0)], 0.0, 0.0);
    field_volume_finish(&v);
    wrf_close(w);
}

static void test_stride_crop_budget(void **state)
{
    struct wrf *w = open_one(KATRINA);
    assert_non_null(w);
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    d.stride[0] = d.stride[1] = 2;
    d.crop[0] = 8;
    d.crop[1] = 39; /* 32 columns, every second: 16 */
    d.crop[4] = 2;
    d.crop[5] = 5;
    struct field_volume v;
    assert_true(wrf_read_step(w, 1, &d, &v, NULL));
    assert_int_equal(v.grid.n[0], 16);
    assert_int_equal(v.grid.n[1], 24);
    assert_int_equal(v.grid.n[2], 4);
    assert_float_equal(v.grid.spacing[0], 20000.0, 1e-9);
    /* Column 8 is centred at 85 km; with 20 km cells the box starts at 75 km. */
    assert_float_equal(v.grid.origin[0], 75000.0, 1e-6);
    field_volume_finish(&v);

    /* A budget below one step is refused, naming the settings that help. */
    wrf_desc_defaults(&d);
    size_t need = wrf_step_bytes(w, &d);
    assert_true(need > 48 * 48 * 14 * 4 * 3);
    d.memory_mb = (double)need / 1048576.0 * 0.5;
    unsigned errors = log_error_count();
    assert_false(wrf_read_step(w, 0, &d, &v, NULL));
    assert_int_equal(log_error_count(), errors + 1);
    assert_non_null(strstr(log_last_error(), "data.stride"));
    assert_non_null(strstr(log_last_error(), "data.crop"));
    assert_null(v.q[SPECIES_CLOUD]);
    d.memory_mb = (double)need / 1048576.0 * 1.01;
    assert_true(wrf_read_step(w, 0, &d, &v, NULL));
    field_volume_finish(&v);

    /* An empty crop is an error, not a crash. */
    wrf_desc_defaults(&d);
    d.crop[0] = 30;
    d.crop[1] = 10;
    assert_false(wrf_read_step(w, 0, &d, &v, NULL));
    assert_false(wrf_read_step(w, 4, &d, &v, NULL));
    wrf_close(w);
}

static void test_resample_column(void **state)
{
    /* Mass levels at 100, 300, 600 m; ground 0 m, model top 800 m. */
    const double z[3] = {100.0, 300.0, 600.0};
    const float v[3] = {1.0f, 3.0f, 6.0f};
    float out[11];
    int below = -1;
    /* Targets -150, -50, 50, ..., 750, 850 m (100 m levels from -200 m). */
    int outside = wrf_resample_column(z, v, 3, 0.0, 800.0, -200.0, 100.0, 11, -1.0f, out, &below);
    assert_int_equal(outside, 3);
    assert_int_equal(below, 2);
    assert_float_equal(out[0], -1.0, 0.0);
    assert_float_equal(out[1], -1.0, 0.0);
    assert_float_equal(out[2], 1.0, 0.0);   /* 50 m: clamped to the first level */
    assert_float_equal(out[3], 1.5, 1e-6);  /* 150 m */
    assert_float_equal(out[4], 2.5, 1e-6);  /* 250 m */
    assert_float_equal(out[5], 3.5, 1e-6);  /* 350 m */
    assert_float_equal(out[7], 5.5, 1e-6);  /* 550 m */
    assert_float_equal(out[8], 6.0, 0.0);   /* 650 m: clamped to the last level */
    assert_float_equal(out[9], 6.0, 0.0);   /* 750 m: still below the model top */
    assert_float_equal(out[10], -1.0, 0.0); /* 850 m: above the top */
    /* Targets on the levels (to 1e-4 dz) take the level's value exactly. */
    const double zr[3] = {50.000001, 150.0, 249.999999};
    const float vr[3] = {0.1f, 0.2f, 0.3f};
    wrf_resample_column(zr, vr, 3, 0.0, 300.0, 0.0, 100.0, 3, -1.0f, out, NULL);
    assert_true(out[0] == 0.1f && out[1] == 0.2f && out[2] == 0.3f);
}

/* ---- malformed files made here -------------------------------------------------------- */

enum defect {
    OK = 0,
    NO_P = 1,
    P_RANK3 = 2,
    QCLOUD_NAN = 4,
    QCLOUD_BAD = 8,  /* a few NaN, Inf, fill, negative and _FillValue values */
    QCLOUD_INT = 16, /* integer type */
};

#define NX 4
#define NY 3
#define NZ 5

#define CHECK(x) assert_int_equal((x), NC_NOERR)

/* A minimal WRF-like file: NT times starting at hour H0, NX x NY x NZ mass grid. */
static const char *make_wrf(const char *name, int nt, int h0, int nz, unsigned defects)
{
    const char *path = test_tmp_path(name);
    char pathcopy[512];
    snprintf(pathcopy, sizeof(pathcopy), "%s", path);
    int nc, dt, ds, dz, dzs, dy, dx;
    CHECK(nc_create(pathcopy, NC_CLOBBER | NC_NETCDF4, &nc));
    CHECK(nc_def_dim(nc, "Time", NC_UNLIMITED, &dt));
    CHECK(nc_def_dim(nc, "DateStrLen", 19, &ds));
    CHECK(nc_def_dim(nc, "west_east", NX, &dx));
    CHECK(nc_def_dim(nc, "south_north", NY, &dy));
    CHECK(nc_def_dim(nc, "bottom_top", nz, &dz));
    CHECK(nc_def_dim(nc, "bottom_top_stag", nz + 1, &dzs));
    float dxy = 1000.0f;
    CHECK(nc_put_att_float(nc, NC_GLOBAL, "DX", NC_FLOAT, 1, &dxy));
    CHECK(nc_put_att_float(nc, NC_GLOBAL, "DY", NC_FLOAT, 1, &dxy));
    int d4[4] = {dt, dz, dy, dx}, d4s[4] = {dt, dzs, dy, dx}, dtimes[2] = {dt, ds};
    int vt, vp, vpb, vth, vph, vphb, vq;
    CHECK(nc_def_var(nc, "Times", NC_CHAR, 2, dtimes, &vt));
    if (!(defects & NO_P))
        CHECK(nc_def_var(nc, "P", NC_FLOAT, (defects & P_RANK3) ? 3 : 4,
                         (defects & P_RANK3) ? d4 + 1 : d4, &vp));
    CHECK(nc_def_var(nc, "PB", NC_FLOAT, 4, d4, &vpb));
    CHECK(nc_def_var(nc, "T", NC_FLOAT, 4, d4, &vth));
    CHECK(nc_def_var(nc, "PH", NC_FLOAT, 4, d4s, &vph));
    CHECK(nc_def_var(nc, "PHB", NC_FLOAT, 4, d4s, &vphb));
    CHECK(nc_def_var(nc, "QCLOUD", (defects & QCLOUD_INT) ? NC_INT : NC_FLOAT, 4, d4, &vq));
    if (defects & QCLOUD_BAD) {
        float fv = -999.0f;
        CHECK(nc_put_att_float(nc, vq, "_FillValue", NC_FLOAT, 1, &fv));
    }
    CHECK(nc_enddef(nc));
    size_t n = (size_t)NX * NY * nz, ns = (size_t)NX * NY * (nz + 1);
    float *a = malloc(ns * sizeof(float));
    for (int t = 0; t < nt; t++) {
        char date[20];
        snprintf(date, sizeof(date), "2020-01-01_%02d:00:00", h0 + t);
        size_t st2[2] = {(size_t)t, 0}, ct2[2] = {1, 19};
        CHECK(nc_put_vara_text(nc, vt, st2, ct2, date));
        size_t st[4] = {(size_t)t, 0, 0, 0}, ct[4] = {1, (size_t)nz, NY, NX};
        size_t cts[4] = {1, (size_t)nz + 1, NY, NX};
        if (!(defects & (NO_P | P_RANK3))) {
            for (size_t i = 0; i < n; i++)
                a[i] = 0.0f;
            CHECK(nc_put_vara_float(nc, vp, st, ct, a));
        }
        for (size_t i = 0; i < n; i++)
            a[i] = 90000.0f - 1000.0f * (float)(i / (NX * NY));
        CHECK(nc_put_vara_float(nc, vpb, st, ct, a));
        for (size_t i = 0; i < ns; i++)
            a[i] = 0.0f;
        CHECK(nc_put_vara_float(nc, vth, st, ct, a));
        CHECK(nc_put_vara_float(nc, vph, st, cts, a));
        for (size_t i = 0; i < ns; i++)
            a[i] = (float)(i / (NX * NY)) * 100.0f * 9.81f;
        CHECK(nc_put_vara_float(nc, vphb, st, cts, a));
        for (size_t i = 0; i < n; i++)
            a[i] = (defects & QCLOUD_NAN) ? NAN : 1e-4f * (float)(t + 1);
        if (defects & QCLOUD_BAD) {
            a[0] = NAN;
            a[1] = INFINITY;
            a[2] = NC_FILL_FLOAT;
            a[3] = -1e-6f;
            a[4] = -999.0f;
            a[5] = 2.0f;
        }
        if (defects & QCLOUD_INT) {
            int *ia = calloc(n, sizeof(int));
            CHECK(nc_put_vara_int(nc, vq, st, ct, ia));
            free(ia);
        } else {
            CHECK(nc_put_vara_float(nc, vq, st, ct, a));
        }
    }
    free(a);
    CHECK(nc_close(nc));
    return test_tmp_path(name);
}

/* Opening PATH fails with one error that names the file and WORD. */
static void expect_open_error(const char *path, const char *word)
{
    unsigned errors = log_error_count();
    struct wrf *w = wrf_open(&path, 1, 0.0);
    assert_null(w);
    assert_int_equal(log_error_count(), errors + 1);
    assert_non_null(strstr(log_last_error(), path));
    if (word)
        assert_non_null(strstr(log_last_error(), word));
}

static void test_good_small_file(void **state)
{
    const char *path = make_wrf("good.nc", 2, 0, NZ, OK);
    struct wrf *w = wrf_open(&path, 1, 0.0);
    assert_non_null(w);
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    struct field_volume v;
    assert_true(wrf_read_step(w, 1, &d, &v, NULL));
    /* Staggered levels every 100 m from 0: mass levels at 50, 150, ...; the regular grid is the
     * identity, so values come through exactly. */
    assert_int_equal(v.grid.n[2], NZ);
    assert_float_equal(v.grid.spacing[2], 100.0, 1e-3);
    for (size_t i = 0; i < grid3_count(&v.grid); i++)
        assert_true(v.q[SPECIES_CLOUD][i] == 2e-4f);
    field_volume_finish(&v);
    wrf_close(w);
}

static void test_bad_values(void **state)
{
    const char *path = make_wrf("badvalues.nc", 1, 0, NZ, QCLOUD_BAD);
    struct wrf *w = wrf_open(&path, 1, 0.0);
    assert_non_null(w);
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    struct field_volume v;
    struct wrf_stats st;
    unsigned warns = log_warn_count();
    assert_true(wrf_read_step(w, 0, &d, &v, &st));
    assert_true(log_warn_count() > warns);
    const struct wrf_var_stats *q = &st.var[WRF_QCLOUD];
    assert_int_equal(q->nan, 1);
    assert_int_equal(q->inf, 1);
    assert_int_equal(q->fill, 2); /* default fill and _FillValue = -999 */
    assert_int_equal(q->negative, 1);
    assert_int_equal(q->absurd, 1);
    assert_int_equal(wrf_var_stats_bad(q), 6);
    assert_float_equal(q->max, 1e-4, 1e-10);
    /* The bad values are on the first level, which is the first output level: zero there. */
    for (int i = 0; i < 6; i++)
        assert_true(v.q[SPECIES_CLOUD][i] == 0.0f);
    assert_true(v.q[SPECIES_CLOUD][6] == 1e-4f);
    field_volume_finish(&v);
    wrf_close(w);
}

static void test_malformed(void **state)
{
    expect_open_error(make_wrf("nop.nc", 1, 0, NZ, NO_P), "P");
    expect_open_error(make_wrf("rank.nc", 1, 0, NZ, P_RANK3), "variable P");
    expect_open_error(make_wrf("int.nc", 1, 0, NZ, QCLOUD_INT), "QCLOUD");

    /* All-NaN field: opens, but reading the step is one error naming the variable. */
    const char *path = make_wrf("nan.nc", 1, 0, NZ, QCLOUD_NAN);
    struct wrf *w = wrf_open(&path, 1, 0.0);
    assert_non_null(w);
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    struct field_volume v;
    unsigned errors = log_error_count();
    assert_false(wrf_read_step(w, 0, &d, &v, NULL));
    assert_int_equal(log_error_count(), errors + 1);
    assert_non_null(strstr(log_last_error(), "QCLOUD"));
    assert_non_null(strstr(log_last_error(), "nan.nc"));
    assert_null(v.q[SPECIES_CLOUD]);
    wrf_close(w);

    /* Not NetCDF at all, a folder, a missing file. */
    expect_open_error(test_write_file("text.nc", "this is not NetCDF\n"), NULL);
    expect_open_error(test_tmpdir(), NULL);
    expect_open_error(test_tmp_path("missing.nc"), NULL);
}

static void copy_truncated(const char *src, const char *dst, double fraction)
{
    FILE *in = fopen(src, "rb");
    assert_non_null(in);
    fseek(in, 0, SEEK_END);
    long len = ftell(in);
    fseek(in, 0, SEEK_SET);
    long keep = (long)(len * fraction);
    char *buf = malloc((size_t)keep);
    assert_int_equal(fread(buf, 1, (size_t)keep, in), (size_t)keep);
    fclose(in);
    FILE *out = fopen(dst, "wb");
    assert_non_null(out);
    fwrite(buf, 1, (size_t)keep, out);
    fclose(out);
    free(buf);
}

static void test_truncated(void **state)
{
    /* The sample truncated at several points: opening or reading fails with an error naming
     * the file, never a crash. */
    const double fractions[] = {0.01, 0.5, 0.9};
    for (int i = 0; i < 3; i++) {
        char name[64];
        snprintf(name, sizeof(name), "trunc%d.nc", i);
        char dst[512];
        snprintf(dst, sizeof(dst), "%s", test_tmp_path(name));
        copy_truncated(test_shared_data(KATRINA), dst, fractions[i]);
        unsigned errors = log_error_count();
        const char *p = dst;
        struct wrf *w = wrf_open(&p, 1, 0.0);
        bool ok = w != NULL;
        if (w) {
            struct wrf_desc d;
            wrf_desc_defaults(&d);
            struct field_volume v;
            for (int s = 0; s < wrf_step_count(w) && ok; s++) {
                ok = wrf_read_step(w, s, &d, &v, NULL);
                field_volume_finish(&v);
            }
            wrf_close(w);
        }
        assert_false(ok);
        assert_true(log_error_count() > errors);
        assert_non_null(strstr(log_last_error(), dst));
    }
}

static void test_many_files(void **state)
{
    /* Two files given out of order are read in time order. */
    char a[512], b[512];
    snprintf(a, sizeof(a), "%s", make_wrf("late.nc", 2, 6, NZ, OK));
    snprintf(b, sizeof(b), "%s", make_wrf("early.nc", 3, 0, NZ, OK));
    const char *paths[2] = {a, b};
    struct wrf *w = wrf_open(paths, 2, 0.0);
    assert_non_null(w);
    assert_int_equal(wrf_step_count(w), 5);
    assert_string_equal(wrf_step_date(w, 0), "2020-01-01_00:00:00");
    assert_string_equal(wrf_step_date(w, 3), "2020-01-01_06:00:00");
    assert_non_null(strstr(wrf_step_path(w, 3), "late.nc"));
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    struct field_volume v;
    assert_true(wrf_read_step(w, 4, &d, &v, NULL)); /* late.nc, its second time */
    assert_true(v.q[SPECIES_CLOUD][0] == 2e-4f);
    field_volume_finish(&v);
    wrf_close(w);

    /* A glob pattern. */
    char pattern[512];
    snprintf(pattern, sizeof(pattern), "%s/*ly.nc", test_tmpdir());
    const char *pp = pattern;
    w = wrf_open(&pp, 1, 0.0);
    assert_non_null(w);
    assert_int_equal(wrf_step_count(w), 3);
    wrf_close(w);

    /* Mismatched grids across files (the time steps of one cannot follow the other's). */
    char c[512];
    snprintf(c, sizeof(c), "%s", make_wrf("other.nc", 1, 12, NZ + 2, OK));
    const char *mixed[2] = {b, c};
    unsigned errors = log_error_count();
    assert_null(wrf_open(mixed, 2, 0.0));
    assert_int_equal(log_error_count(), errors + 1);
    assert_non_null(strstr(log_last_error(), "other.nc"));

    /* The same time in two files. */
    char e[512];
    snprintf(e, sizeof(e), "%s", make_wrf("dup.nc", 1, 1, NZ, OK));
    const char *dup[2] = {b, e};
    assert_null(wrf_open(dup, 2, 0.0));
    assert_non_null(strstr(log_last_error(), "2020-01-01_01:00:00"));
}

/* ---- round trip through the writer ---------------------------------------------------- */

static void test_synth_round_trip(void **state)
{
    char path[512];
    snprintf(path, sizeof(path), "%s", test_tmp_path("synth.nc"));
    struct synth_desc sd = {
        .kind = SYNTH_STORM, .n = {40, 30, 20}, .extent_m = {60000.0, 45000.0, 16000.0}, .seed = 7};
    struct wrf_write_desc wd = {.cen_lat = 25.0, .cen_lon = -89.0};
    struct field_volume in[3];
    struct wrf_writer *ww = NULL;
    const char *dates[3] = {"2000-01-01_00:00:00", "2000-01-01_00:10:00", "2000-01-01_00:20:00"};
    for (int s = 0; s < 3; s++) {
        sd.time = s / 2.0;
        assert_true(synth_storm_fields(&sd, &in[s]));
        if (!ww) {
            ww = wrf_writer_create(path, &in[0].grid, &wd);
            assert_non_null(ww);
        }
        assert_true(wrf_writer_add(ww, &in[s], dates[s]));
    }
    assert_true(wrf_writer_finish(ww));

    const char *p = path;
    struct wrf *w = wrf_open(&p, 1, 0.0);
    assert_non_null(w);
    const struct wrf_meta *m = wrf_get_meta(w);
    assert_int_equal(m->nx, 40);
    assert_int_equal(m->nz, 20);
    assert_int_equal(m->map_proj, 3);
    assert_int_equal(m->mp_physics, 8);
    assert_float_equal(m->dx, 1500.0, 1e-3);
    assert_true(m->lat_min < 25.0 && m->lat_max > 25.0);
    assert_true(m->lon_min < -89.0 && m->lon_max > -89.0);
    assert_int_equal(wrf_step_count(w), 3);
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    for (int s = 0; s < 3; s++) {
        assert_string_equal(wrf_step_date(w, s), dates[s]);
        struct field_volume out;
        struct wrf_stats st;
        assert_true(wrf_read_step(w, s, &d, &out, &st));
        size_t n = grid3_count(&out.grid);
        for (int a = 0; a < 3; a++) {
            assert_int_equal(out.grid.n[a], in[s].grid.n[a]);
            assert_float_equal(out.grid.spacing[a], in[s].grid.spacing[a],
                               1e-6 * in[s].grid.spacing[a]);
            assert_float_equal(out.grid.origin[a], in[s].grid.origin[a], 1e-3);
        }
        assert_int_equal(st.below_terrain + st.above_top, 0);
        for (int f = 0; f < SPECIES_COUNT; f++) {
            assert_non_null(out.q[f]);
            /* Exact: the heights are the regular grid, so the resampling is the identity. */
            assert_memory_equal(out.q[f], in[s].q[f], n * sizeof(float));
        }
        /* Standard atmosphere through P, PB, T and back. */
        for (int k = 0; k < out.grid.n[2]; k++) {
            double z = (k + 0.5) * out.grid.spacing[2];
            double rho = optics_std_atmosphere_density(z);
            float got = out.rho_air[grid3_index(&out.grid, 3, 4, k)];
            assert_float_equal(got, rho, rho * 1e-3);
        }
        field_volume_finish(&out);
        field_volume_finish(&in[s]);
    }
    wrf_close(w);
}

static void test_partial_species_round_trip(void **state)
{
    /* Two species, vapour and air density given: all come back (density to float rounding). */
    struct grid3 g = {.n = {6, 5, 8}, .spacing = {500.0, 700.0, 300.0}, .origin = {0, 0, 0}};
    size_t n = grid3_count(&g);
    struct field_volume v = {.grid = g};
    v.q[SPECIES_CLOUD] = malloc(n * sizeof(float));
    v.q[SPECIES_RAIN] = malloc(n * sizeof(float));
    v.qvapor = malloc(n * sizeof(float));
    v.rho_air = malloc(n * sizeof(float));
    for (size_t i = 0; i < n; i++) {
        v.q[SPECIES_CLOUD][i] = 1e-5f * (float)(i % 17);
        v.q[SPECIES_RAIN][i] = 3e-6f * (float)(i % 5);
        v.qvapor[i] = 0.012f - 1e-5f * (float)i;
        v.rho_air[i] = 1.2f - 0.0005f * (float)i;
    }
    char path[512];
    snprintf(path, sizeof(path), "%s", test_tmp_path("partial.nc"));
    struct wrf_writer *ww = wrf_writer_create(path, &g, NULL);
    assert_true(wrf_writer_add(ww, &v, "2001-02-03_04:05:06"));
    assert_true(wrf_writer_finish(ww));
    const char *p = path;
    struct wrf *w = wrf_open(&p, 1, 0.0);
    assert_non_null(w);
    assert_int_equal(wrf_get_meta(w)->mp_physics, 3);
    assert_false(wrf_get_meta(w)->has_species[SPECIES_ICE]);
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    d.qvapor = true;
    struct field_volume out;
    assert_true(wrf_read_step(w, 0, &d, &out, NULL));
    assert_memory_equal(out.q[SPECIES_CLOUD], v.q[SPECIES_CLOUD], n * sizeof(float));
    assert_memory_equal(out.q[SPECIES_RAIN], v.q[SPECIES_RAIN], n * sizeof(float));
    assert_memory_equal(out.qvapor, v.qvapor, n * sizeof(float));
    assert_null(out.q[SPECIES_SNOW]);
    for (size_t i = 0; i < n; i++)
        assert_float_equal(out.rho_air[i], v.rho_air[i], 1e-5);
    field_volume_finish(&out);
    wrf_close(w);

    /* A later step with other species is refused; the failed write leaves no file. */
    char p2[512];
    snprintf(p2, sizeof(p2), "%s", test_tmp_path("partial2.nc"));
    ww = wrf_writer_create(p2, &g, NULL);
    assert_true(wrf_writer_add(ww, &v, "2001-02-03_04:05:06"));
    float *keep = v.q[SPECIES_RAIN];
    v.q[SPECIES_RAIN] = NULL;
    assert_false(wrf_writer_add(ww, &v, "2001-02-03_05:05:06"));
    v.q[SPECIES_RAIN] = keep;
    assert_false(wrf_writer_finish(ww));
    assert_int_equal(access(p2, F_OK), -1);
    field_volume_finish(&v);
}

/* One 500 x 500 x 100 step (the Isabel size) fits the default budget the way the reader
 * counts it, and a budget of a quarter of that is refused. */
static void test_isabel_size_budget(void **state)
{
    struct grid3 g = {.n = {500, 500, 2}, .spacing = {4000.0, 4000.0, 200.0}};
    size_t n = grid3_count(&g);
    struct field_volume v = {.grid = g};
    for (int f = 0; f < SPECIES_COUNT; f++)
        v.q[f] = calloc(n, sizeof(float));
    char path[512];
    snprintf(path, sizeof(path), "%s", test_tmp_path("wide.nc"));
    struct wrf_writer *ww = wrf_writer_create(path, &g, NULL);
    assert_true(wrf_writer_add(ww, &v, "2004-09-15_00:00:00"));
    assert_true(wrf_writer_finish(ww));
    field_volume_finish(&v);
    const char *p = path;
    struct wrf *w = wrf_open(&p, 1, 0.0);
    assert_non_null(w);
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    d.levels = 100;
    /* 5 species + density on 500 x 500 x 100 outputs, plus each CPU's scratch for one slab
     * of 4000 columns: 2 staggered and 2 mass-level input levels, the slab's resampling plan
     * (6 bytes per output voxel), a few bytes per slab for what it found. */
    size_t need = wrf_step_bytes(w, &d), arrays = 6 * 25000000ul * 4;
    size_t per_cpu = 4000ul * (2 * 3 + 2) * 4 + 4000ul * 100 * 6;
    assert_true(need >= arrays + per_cpu);
    assert_true(need <= arrays + 16 * per_cpu + 125 * 4096);
    assert_true(need < 1024ul * 1048576ul);
    d.memory_mb = 1024.0;
    struct field_volume out;
    assert_true(wrf_read_step(w, 0, &d, &out, NULL));
    assert_int_equal(out.grid.n[2], 100);
    field_volume_finish(&out);
    d.memory_mb = 256.0;
    assert_false(wrf_read_step(w, 0, &d, &out, NULL));
    assert_non_null(strstr(log_last_error(), "data.stride"));
    wrf_close(w);
}

int main(void)
{
    log_set_level(LOG_ERROR);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_katrina_meta),
        cmocka_unit_test(test_katrina_moves),
        cmocka_unit_test(test_katrina_step),
        cmocka_unit_test(test_katrina_spot_values),
        cmocka_unit_test(test_lambert),
        cmocka_unit_test(test_stride_crop_budget),
        cmocka_unit_test(test_resample_column),
        cmocka_unit_test(test_good_small_file),
        cmocka_unit_test(test_bad_values),
        cmocka_unit_test(test_malformed),
        cmocka_unit_test(test_truncated),
        cmocka_unit_test(test_many_files),
        cmocka_unit_test(test_synth_round_trip),
        cmocka_unit_test(test_partial_species_round_trip),
        cmocka_unit_test(test_isabel_size_budget),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
