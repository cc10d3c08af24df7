/* The probe (docs/analysis.md): anvil probe on the Katrina sample at a grid point returns the
 * file's values there, read here with netcdf-c (mass ratios on a model level and between two,
 * the temperature against T = (theta' + 300) (p / p0)^(R/cp), pressure, wind), the wind turned
 * to east and north with COSALPHA and SINALPHA on a Lambert grid; the first visible point
 * along a ray through a known ramp; trilinear sampling; wind directions; the histogram behind
 * the transfer function editor against counts made here. */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <netcdf.h>

#include "common/log.h"
#include "config/config.h"
#include "data/probe.h"
#include "data/wrf.h"
#include "data/wrf_write.h"
#include "session/player.h"

#define CHECK(x) assert_int_equal((x), NC_NOERR)
#define P0 100000.0
#define R_CP (287.0 / 1004.5) /* R_d / c_p of WRF's module_model_constants.F: 2/7 */

static const char *katrina(void)
{
    return test_shared_data("wrf/katrina_2005_mercator_wsm3.nc");
}

/* One value of a 4-D variable (Time, level, south_north, west_east). */
static float at4(int nc, const char *name, int t, int k, int j, int i)
{
    int v;
    CHECK(nc_inq_varid(nc, name, &v));
    size_t start[4] = {(size_t)t, (size_t)k, (size_t)j, (size_t)i}, one[4] = {1, 1, 1, 1};
    float x;
    CHECK(nc_get_vara_float(nc, v, start, one, &x));
    return x;
}

/* One value of a 2-D variable (south_north, west_east), with or without a leading Time (the
 * first then). */
/* A 2-D field at column (I, J) of time T (the first time for a field without one). */
static float at2t(int nc, const char *name, int t, int j, int i)
{
    int v, ndims;
    CHECK(nc_inq_varid(nc, name, &v));
    CHECK(nc_inq_varndims(nc, v, &ndims));
    size_t start[3] = {(size_t)t, (size_t)j, (size_t)i}, one[3] = {1, 1, 1};
    float x;
    CHECK(nc_get_vara_float(nc, v, ndims == 3 ? start : start + 1, one, &x));
    return x;
}

static float at2(int nc, const char *name, int j, int i)
{
    int v, ndims;
    CHECK(nc_inq_varid(nc, name, &v));
    CHECK(nc_inq_varndims(nc, v, &ndims));
    size_t start[3] = {0, (size_t)j, (size_t)i}, one[3] = {1, 1, 1};
    float x;
    CHECK(nc_get_vara_float(nc, v, ndims == 3 ? start : start + 1, one, &x));
    return x;
}

/* The number after "KEY": in TEXT; NAN for null; fails when absent. */
static double json_number(const char *text, const char *key)
{
    char pat[96];
    snprintf(pat, sizeof(pat), "\"%s\": ", key);
    const char *p = strstr(text, pat);
    if (!p)
        fail_msg("no \"%s\" in %s", key, text);
    p += strlen(pat);
    if (strncmp(p, "null", 4) == 0)
        return NAN;
    return strtod(p, NULL);
}

/* anvil probe ARGS --json: its output (static buffer); fails unless it exits 0. */
static const char *probe_json(const char *args)
{
    const char *bin = getenv("ANVIL_BIN");
    if (!bin)
        skip();
    static char out[8192];
    char cmd[2048];
    snprintf(cmd, sizeof(cmd), "'%s' --quiet probe %s --json", bin, args);
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    size_t n = fread(out, 1, sizeof(out) - 1, p);
    out[n] = '\0';
    int rc = pclose(p);
    if (rc != 0)
        fail_msg("%s exited %d: %s", cmd, rc, out);
    return out;
}

/* Column (I, J) at time T as the reader sees it: the staggered heights (PH + PHB) / g rounded
 * to float, the mass levels' heights (the mean of their faces). */
struct column {
    int nz;
    double zw[64], zm[64];
};

static void column_of(int nc, int t, int i, int j, int nz, struct column *c)
{
    c->nz = nz;
    for (int k = 0; k <= nz; k++)
        c->zw[k] = (float)(((double)at4(nc, "PH", t, k, j, i) +
                            (double)at4(nc, "PHB", t, k, j, i)) /
                           9.81);
    for (int k = 0; k < nz; k++)
        c->zm[k] = 0.5 * (c->zw[k] + c->zw[k + 1]);
}

/* The vertical mapping of docs/data.md at height Z of values V on the column's mass levels:
 * linear in height between the two levels around Z, the first level's value below it, the
 * last one's above it. */
static double mapped(const struct column *c, const double *v, double z)
{
    if (z <= c->zm[0])
        return v[0];
    if (z >= c->zm[c->nz - 1])
        return v[c->nz - 1];
    int k = 0;
    while (c->zm[k + 1] <= z)
        k++;
    double t = (z - c->zm[k]) / (c->zm[k + 1] - c->zm[k]);
    return (1.0 - t) * v[k] + t * v[k + 1];
}

/* The height grid's top: the highest model top of the first time over all columns. */
static double auto_top(int nc, int nx, int ny, int nz)
{
    double top = 0.0;
    for (int j = 0; j < ny; j++)
        for (int i = 0; i < nx; i++)
            top = fmax(top, ((double)at4(nc, "PH", 0, nz, j, i) + (double)at4(nc, "PHB", 0, nz, j, i)) /
                                9.81);
    return top;
}

/* A variable on the mass levels of column (I, J) at time T. */
static void levels_of(int nc, const char *name, int t, int i, int j, int nz, double *v)
{
    for (int k = 0; k < nz; k++)
        v[k] = at4(nc, name, t, k, j, i);
}

static double rel(double a, double b)
{
    return fabs(a - b) / fmax(fabs(b), 1e-30);
}

static void test_katrina_grid_point(void **state)
{
    int nc;
    CHECK(nc_open(katrina(), NC_NOWRITE, &nc));
    int d;
    size_t nx, ny, nz;
    CHECK(nc_inq_dimid(nc, "west_east", &d));
    CHECK(nc_inq_dimlen(nc, d, &nx));
    CHECK(nc_inq_dimid(nc, "south_north", &d));
    CHECK(nc_inq_dimlen(nc, d, &ny));
    CHECK(nc_inq_dimid(nc, "bottom_top", &d));
    CHECK(nc_inq_dimlen(nc, d, &nz));
    assert_true(nz < 63);
    const int t = 1;
    /* The regular height grid the reader makes: as many levels as the model, to its top. */
    double dz = auto_top(nc, (int)nx, (int)ny, (int)nz) / (double)nz;
    /* The cloudiest point of the height grid at step 1, away from the edges and the top. */
    int bi = 0, bj = 0, bk = 0;
    double best = -1.0;
    struct column c;
    double qc[64];
    for (int j = 2; j + 2 < (int)ny; j++)
        for (int i = 2; i + 2 < (int)nx; i++) {
            column_of(nc, t, i, j, (int)nz, &c);
            levels_of(nc, "QCLOUD", t, i, j, (int)nz, qc);
            for (int k = 0; k + 1 < (int)nz; k++) {
                double z = (k + 0.5) * dz;
                double q = z > c.zw[0] ? mapped(&c, qc, z) : 0.0;
                if (q > best)
                    best = q, bi = i, bj = j, bk = k;
            }
        }
    assert_true(best > 1e-5);
    /* The column's position at that step: the sample is a moving nest. */
    float lat = at2t(nc, "XLAT", t, bj, bi), lon = at2t(nc, "XLONG", t, bj, bi);
    column_of(nc, t, bi, bj, (int)nz, &c);
    double qr[64], p[64], temp[64], u[64], v[64], w[64];
    levels_of(nc, "QCLOUD", t, bi, bj, (int)nz, qc);
    levels_of(nc, "QRAIN", t, bi, bj, (int)nz, qr);
    for (int k = 0; k < (int)nz; k++) {
        p[k] = (double)at4(nc, "P", t, k, bj, bi) + (double)at4(nc, "PB", t, k, bj, bi);
        /* T = (theta' + 300) (p / p0)^(R/cp) */
        temp[k] = ((double)at4(nc, "T", t, k, bj, bi) + 300.0) * pow(p[k] / P0, R_CP);
        u[k] = 0.5 * ((double)at4(nc, "U", t, k, bj, bi) + (double)at4(nc, "U", t, k, bj, bi + 1));
        v[k] = 0.5 * ((double)at4(nc, "V", t, k, bj, bi) + (double)at4(nc, "V", t, k, bj + 1, bi));
        w[k] = 0.5 * ((double)at4(nc, "W", t, k, bj, bi) + (double)at4(nc, "W", t, k + 1, bj, bi));
    }

    /* At a voxel centre of the height grid: the file's values after the vertical mapping, to
     * float rounding (the volume holds floats). */
    double z = (bk + 0.5) * dz;
    char args[1024];
    /* (The uniform height grid, whose voxel centres are these.) */
    snprintf(args, sizeof(args),
             "'%s/configs/katrina.cfg' --at %.17g,%.17g,%.17g --step %d --set data.vertical=uniform",
             ANVIL_SOURCE_DIR, (double)lat, (double)lon, z, t);
    const char *js = probe_json(args);
    assert_true(strstr(js, "\"valid\": true") != NULL);
    assert_true(strstr(js, "\"temperature_source\": \"data\"") != NULL);
    double cloud = mapped(&c, qc, z), rain = mapped(&c, qr, z);
    assert_true(rel(json_number(js, "cloud"), cloud * 1e3) < 1e-6);
    assert_true(rel(json_number(js, "rain"), rain * 1e3) < 1e-6 || (rain < 1e-12 && json_number(js, "rain") < 1e-9));
    assert_true(isnan(json_number(js, "ice"))); /* WSM3 writes no ice: null */
    assert_true(rel(json_number(js, "condensate_g_per_kg"), (cloud + rain) * 1e3) < 1e-6);
    assert_true(fabs(json_number(js, "temperature_c") - (mapped(&c, temp, z) - 273.15)) < 1e-4);
    assert_true(rel(json_number(js, "pressure_hpa"), mapped(&c, p, z) / 100.0) < 1e-6);
    /* Mercator: the grid's x and y are east and north. */
    double ue = mapped(&c, u, z), ve = mapped(&c, v, z);
    assert_true(strstr(js, "\"earth_relative\": true") != NULL);
    assert_true(fabs(json_number(js, "u_m_s") - ue) < 1e-4);
    assert_true(fabs(json_number(js, "v_m_s") - ve) < 1e-4);
    assert_true(fabs(json_number(js, "speed_m_s") - hypot(ue, ve)) < 1e-4);
    double from = fmod(atan2(-ue, -ve) * 180.0 / M_PI + 360.0, 360.0);
    assert_true(fabs(json_number(js, "from_deg") - from) < 1e-3);
    assert_true(fabs(json_number(js, "w_m_s") - mapped(&c, w, z)) < 1e-5);
    assert_true(fabs(json_number(js, "latitude_deg") - lat) < 1e-6);
    assert_true(fabs(json_number(js, "height_m") - z) < 1e-6);
    assert_true(fabs(json_number(js, "ground_m") - c.zw[0]) < 1e-3);
    /* A cloudy point: the volume drawn there is not clear, and it is in the shade of something
     * or lit: a light map's value in [0, 1]. */
    assert_true(json_number(js, "total") > 1e-5);
    double light = json_number(js, "light");
    assert_true(light >= 0.0 && light <= 1.0);

    /* 30 % of the way up to the next voxel centre: linear between the two, as the eye pass
     * samples. */
    double z1 = z + 0.3 * dz;
    snprintf(args, sizeof(args),
             "'%s/configs/katrina.cfg' --at %.17g,%.17g,%.17g --step %d --set data.vertical=uniform",
             ANVIL_SOURCE_DIR, (double)lat, (double)lon, z1, t);
    js = probe_json(args);
    double cloud1 = mapped(&c, qc, z + dz);
    assert_true(rel(json_number(js, "cloud"), (0.7 * cloud + 0.3 * cloud1) * 1e3) < 1e-6);
    double t1 = 0.7 * mapped(&c, temp, z) + 0.3 * mapped(&c, temp, z + dz);
    assert_true(fabs(json_number(js, "temperature_c") - (t1 - 273.15)) < 1e-4);
    CHECK(nc_close(nc));
}

/* A rotated grid: U, V turned east and north with COSALPHA and SINALPHA. */
static void test_lambert_wind_turned(void **state)
{
    const char *path = test_shared_data("wrf/lambert_thompson_cropped.nc");
    int nc;
    CHECK(nc_open(path, NC_NOWRITE, &nc));
    size_t nz, nx, ny;
    int dim;
    CHECK(nc_inq_dimid(nc, "bottom_top", &dim));
    CHECK(nc_inq_dimlen(nc, dim, &nz));
    CHECK(nc_inq_dimid(nc, "west_east", &dim));
    CHECK(nc_inq_dimlen(nc, dim, &nx));
    CHECK(nc_inq_dimid(nc, "south_north", &dim));
    CHECK(nc_inq_dimlen(nc, dim, &ny));
    /* The column inside the grid where it is turned most. */
    int i = 1, j = 1;
    for (int jj = 1; jj + 1 < (int)ny; jj++)
        for (int ii = 1; ii + 1 < (int)nx; ii++)
            if (fabsf(at2(nc, "SINALPHA", jj, ii)) > fabsf(at2(nc, "SINALPHA", j, i)))
                i = ii, j = jj;
    float lat = at2(nc, "XLAT", j, i), lon = at2(nc, "XLONG", j, i);
    float ca = at2(nc, "COSALPHA", j, i), sa = at2(nc, "SINALPHA", j, i);
    assert_true(fabsf(sa) > 1e-2f); /* a grid that is turned here */
    struct column c;
    column_of(nc, 0, i, j, (int)nz, &c);
    double dz = auto_top(nc, (int)nx, (int)ny, (int)nz) / (double)nz;
    int k = 0;
    while ((k + 0.5) * dz < c.zw[0] + 500.0)
        k++; /* well above the (Tibetan) ground */
    double z = (k + 0.5) * dz, u[64], v[64];
    for (int l = 0; l < (int)nz; l++) {
        u[l] = 0.5 * ((double)at4(nc, "U", 0, l, j, i) + (double)at4(nc, "U", 0, l, j, i + 1));
        v[l] = 0.5 * ((double)at4(nc, "V", 0, l, j, i) + (double)at4(nc, "V", 0, l, j + 1, i));
    }
    double ug = mapped(&c, u, z), vg = mapped(&c, v, z);
    CHECK(nc_close(nc));
    char args[1024];
    snprintf(args, sizeof(args), "'%s' --at %.17g,%.17g,%.17g --set data.vertical=uniform", path,
             (double)lat, (double)lon, z);
    const char *js = probe_json(args);
    assert_true(strstr(js, "\"earth_relative\": true") != NULL);
    assert_true(fabs(json_number(js, "u_m_s") - (ug * ca - vg * sa)) < 1e-4);
    assert_true(fabs(json_number(js, "v_m_s") - (vg * ca + ug * sa)) < 1e-4);
    assert_true(fabs(json_number(js, "speed_m_s") - hypot(ug, vg)) < 1e-4);
    /* The turn is large enough here that the unturned wind would fail. */
    assert_true(fabs(ug * ca - vg * sa - ug) > 1e-3 || fabs(vg * ca + ug * sa - vg) > 1e-3);
}

/* A point read from the file's columns equals the field volume wrf_read_step makes, sampled
 * there (the volume the picture is made from), whole or cropped and strided. */
static void test_point_is_the_volume(void **state)
{
    const char *files[] = {katrina()};
    struct wrf *w = wrf_open(files, 1, 4096.0);
    assert_non_null(w);
    for (int pass = 0; pass < 2; pass++) {
        struct wrf_desc d;
        wrf_desc_defaults(&d);
        d.temperature = true;
        if (pass == 1) {
            d.stride[0] = d.stride[1] = 2;
            d.crop[0] = 3, d.crop[1] = 40, d.crop[2] = 5, d.crop[3] = 44;
            d.levels = 20;
        }
        struct field_volume fv;
        log_set_level(LOG_ERROR);
        assert_true(wrf_read_step(w, 1, &d, &fv, NULL));
        log_set_level(LOG_INFO);
        const struct grid3 *g = &fv.grid;
        unsigned seed = 7;
        int compared = 0;
        for (int n = 0; n < 400; n++) {
            double p[3];
            for (int a = 0; a < 3; a++) {
                seed = seed * 1103515245u + 12345u;
                p[a] = g->origin[a] + g->n[a] * g->spacing[a] * ((seed >> 8) & 0xffff) / 65536.0;
            }
            struct wrf_point wp;
            enum wrf_point_result r = wrf_read_point(w, 1, &d, p, &wp);
            assert_true(r == WRF_POINT_OK || r == WRF_POINT_BELOW || r == WRF_POINT_ABOVE);
            if (r != WRF_POINT_OK)
                continue;
            struct probe_sample s;
            assert_true(probe_sample_fields(&fv, p, &s));
            for (int f = 0; f < SPECIES_COUNT; f++) {
                assert_int_equal(wp.has_species[f], s.has_species[f]);
                assert_true(fabs(wp.q[f] - s.q[f]) <= 1e-6 * fabs(s.q[f]) + 1e-12);
            }
            assert_true(fabs(wp.temperature_k - s.temperature_k) < 1e-3);
            compared++;
        }
        assert_true(compared > 200);
        field_volume_finish(&fv);
    }
    wrf_close(w);
}

static void test_wind_direction(void **state)
{
    double speed, from;
    probe_wind(10.0, 0.0, &speed, &from); /* blowing east: from the west */
    assert_true(speed == 10.0 && fabs(from - 270.0) < 1e-12);
    probe_wind(0.0, 5.0, &speed, &from); /* blowing north: a southerly */
    assert_true(fabs(from - 180.0) < 1e-12);
    probe_wind(0.0, -5.0, &speed, &from);
    assert_true(fabs(from) < 1e-12);
    probe_wind(-3.0, 0.0, &speed, &from);
    assert_true(fabs(from - 90.0) < 1e-12);
    probe_wind(1.0, 1.0, &speed, &from); /* toward the north-east: from the south-west */
    assert_true(fabs(from - 225.0) < 1e-12 && fabs(speed - sqrt(2.0)) < 1e-12);
    probe_wind(0.0, 0.0, &speed, &from);
    assert_true(speed == 0.0 && from == 0.0);
}

/* 8 x 4 x 4 voxels of 100 m; water extinction B0 from voxel i = 5 on.  Between voxel centres
 * 4 (450 m) and 5 (550 m) it ramps linearly, so B0 / 4 is crossed at 475 m. */
static void test_first_visible(void **state)
{
    struct grid3 g = {.n = {8, 4, 4}, .spacing = {100, 100, 100}, .origin = {0, 0, 0}};
    struct ext_volume v;
    assert_true(ext_volume_init(&v, &g));
    const float b0 = 0.02f;
    for (int k = 0; k < 4; k++)
        for (int j = 0; j < 4; j++)
            for (int i = 5; i < 8; i++)
                v.beta[2 * grid3_index(&g, i, j, k) + 1] = b0;
    double t;
    const double o[3] = {-250.0, 200.0, 200.0}, d[3] = {1.0, 0.0, 0.0};
    assert_true(probe_first_visible(&v, o, d, 1e4, b0 / 4.0, &t));
    assert_true(fabs(t - 725.0) < 0.01); /* 250 m to the box, then 475 m in */
    /* Too far for T_MAX; a threshold never reached; a ray that misses the box. */
    assert_false(probe_first_visible(&v, o, d, 700.0, b0 / 4.0, &t));
    assert_false(probe_first_visible(&v, o, d, 1e4, 2.0 * b0, &t));
    const double up[3] = {0.0, 0.0, 1.0}, beside[3] = {-250.0, 900.0, 200.0};
    assert_false(probe_first_visible(&v, beside, d, 1e4, b0 / 4.0, &t));
    /* From inside the cloud: at once. */
    const double inside[3] = {700.0, 200.0, 10.0};
    assert_true(probe_first_visible(&v, inside, up, 1e4, b0 / 4.0, &t) && t == 0.0);
    /* The sample there: trilinear between centres, clamped at the edges, zero outside. */
    double b[2];
    probe_sample_beta(&v, (const double[3]){475.0, 200.0, 200.0}, b);
    assert_true(b[0] == 0.0 && fabs(b[1] - b0 / 4.0) < 1e-9);
    probe_sample_beta(&v, (const double[3]){799.0, 1.0, 399.0}, b);
    assert_true(fabs(b[1] - b0) < 1e-9);
    probe_sample_beta(&v, (const double[3]){801.0, 1.0, 1.0}, b);
    assert_true(b[1] == 0.0);
    ext_volume_finish(&v);
}

/* A field volume read at voxel centres gives the voxels' values, between them the mean. */
static void test_sample_fields(void **state)
{
    struct field_volume fv = {.grid = {.n = {3, 2, 2}, .spacing = {10, 10, 10}}};
    size_t n = grid3_count(&fv.grid);
    fv.q[SPECIES_RAIN] = calloc(n, sizeof(float));
    for (size_t i = 0; i < n; i++)
        fv.q[SPECIES_RAIN][i] = (float)(1e-4 * (double)i);
    struct probe_sample s;
    assert_true(probe_sample_fields(&fv, (const double[3]){15.0, 5.0, 15.0}, &s));
    assert_true(s.has_species[SPECIES_RAIN] && !s.has_species[SPECIES_CLOUD]);
    assert_true(fabs(s.q[SPECIES_RAIN] - fv.q[SPECIES_RAIN][grid3_index(&fv.grid, 1, 0, 1)]) <
                1e-12);
    assert_true(probe_sample_fields(&fv, (const double[3]){10.0, 5.0, 5.0}, &s));
    double mean = 0.5 * (fv.q[SPECIES_RAIN][0] + fv.q[SPECIES_RAIN][1]);
    assert_true(fabs(s.q[SPECIES_RAIN] - mean) < 1e-12);
    assert_true(s.temperature_from == PROBE_STANDARD && s.pressure_from == PROBE_STANDARD);
    assert_false(probe_sample_fields(&fv, (const double[3]){31.0, 5.0, 5.0}, &s));
    field_volume_finish(&fv);
}

/* CM1's and CF's pressure is the file's: synth's files (the standard atmosphere) with their
 * pressure scaled by 1.01 here, probed at 3 km: 1.01 x the standard atmosphere there, said to
 * come from the data (before, the probe gave the standard atmosphere whatever the file held). */
static void test_height_level_pressure_is_the_files(void **state)
{
    const char *bin = getenv("ANVIL_BIN");
    if (!bin)
        skip();
    const char *formats[2] = {"cm1", "cf"}, *names[2] = {"prs", "pa"};
    for (int f = 0; f < 2; f++) {
        const char *path = test_tmp_path(f ? "p-cf.nc" : "p-cm1.nc");
        char cmd[1024];
        snprintf(cmd, sizeof(cmd), "'%s' --quiet synth --format %s --size 16x16x20 -o '%s'", bin,
                 formats[f], path);
        assert_int_equal(system(cmd), 0);
        int nc, v, nd, dims[4];
        CHECK(nc_open(path, NC_WRITE, &nc));
        CHECK(nc_inq_varid(nc, names[f], &v));
        CHECK(nc_inq_varndims(nc, v, &nd));
        CHECK(nc_inq_vardimid(nc, v, dims));
        size_t count = 1;
        for (int d = 0; d < nd; d++) {
            size_t len;
            CHECK(nc_inq_dimlen(nc, dims[d], &len));
            count *= len;
        }
        float *a = malloc(count * sizeof(float));
        assert_non_null(a);
        CHECK(nc_get_var_float(nc, v, a));
        for (size_t i = 0; i < count; i++)
            a[i] *= 1.01f;
        CHECK(nc_put_var_float(nc, v, a));
        free(a);
        CHECK(nc_close(nc));
        char args[1200];
        snprintf(args, sizeof(args), "'%s' --at 25.2,-79.8,3000 --set map.use_origin=true", path);
        const char *js = probe_json(args);
        assert_non_null(strstr(js, "\"pressure_source\": \"data\""));
        double t_std, p_std;
        wrf_std_atmosphere(3000.0, &t_std, &p_std);
        double hpa = json_number(js, "pressure_hpa");
        /* Linear between the levels: within 0.3 % of it; the standard atmosphere is 1 % off. */
        if (!(fabs(hpa - 1.01 * p_std / 100.0) < 0.003 * 1.01 * p_std / 100.0))
            fail_msg("%s: %g hPa, expected about %g", formats[f], hpa, 1.01 * p_std / 100.0);
    }
}

/* The counts of a histogram made here, by the rule the header gives. */
static void count_here(const float *v, size_t n, double lo, double hi, uint32_t *count,
                       uint64_t *below, uint64_t *above)
{
    memset(count, 0, sizeof(uint32_t) * TRANSFER_HISTOGRAM_BINS);
    *below = *above = 0;
    for (size_t i = 0; i < n; i++) {
        if (v[i] < lo)
            (*below)++;
        else if (v[i] > hi)
            (*above)++;
        else {
            int b = (int)floor((v[i] - lo) / (hi - lo) * TRANSFER_HISTOGRAM_BINS);
            count[b >= TRANSFER_HISTOGRAM_BINS ? TRANSFER_HISTOGRAM_BINS - 1 : b]++;
        }
    }
}

/* The histogram the player makes with a step's volume (the editor's bars) counts the field of
 * that step: QVAPOR by default, the temperature when the look's transfer function is of it. */
static void test_histogram_counts(void **state)
{
    static struct config cfg;
    char path[1024];
    snprintf(path, sizeof(path), "%s/configs/katrina.cfg", ANVIL_SOURCE_DIR);
    const char *sets[] = {"data.step=2"};
    test_config_file(&cfg, path, sets, 1);
    for (int pass = 0; pass < 2; pass++) {
        if (pass == 1) {
            cfg.look.has_transfer = true;
            cfg.look.show_transfer = false; /* counted even while the clouds show */
            transfer_defaults(&cfg.look.transfer, TRANSFER_FIELD_TEMPERATURE);
        }
        log_set_level(LOG_ERROR);
        /* Without a menu to show it, no histogram is made. */
        log_set_level(LOG_ERROR);
        struct player *p = player_create(&cfg, &(struct player_desc){.still = true});
        log_set_level(LOG_INFO);
        assert_non_null(p);
        struct ext_volume vol;
        assert_true(player_take_first(p, &vol));
        assert_null(vol.histogram);
        ext_volume_finish(&vol);
        player_destroy(p);
        log_set_level(LOG_ERROR);
        p = player_create(&cfg, &(struct player_desc){.still = true, .histogram = true});
        log_set_level(LOG_INFO);
        assert_non_null(p);
        assert_true(player_take_first(p, &vol));
        assert_non_null(vol.histogram);
        const struct transfer_histogram *h = vol.histogram;
        /* The same step's field, read here, counted here. */
        const char *files[] = {cfg.data.files[0]};
        struct wrf *w = wrf_open(files, 1, 4096.0);
        assert_non_null(w);
        struct wrf_desc d;
        wrf_desc_defaults(&d);
        d.qvapor = true;
        d.native_levels = true; /* as the config (data.vertical's default) */
        d.temperature = pass == 1;
        struct field_volume fv;
        log_set_level(LOG_ERROR);
        assert_true(wrf_read_step(w, 2, &d, &fv, NULL));
        log_set_level(LOG_INFO);
        const float *field = pass == 0 ? fv.qvapor : fv.temperature;
        double lo = pass == 0 ? 0.0 : 200.0, hi = pass == 0 ? 0.012 : 310.0;
        assert_int_equal(h->field, pass == 0 ? TRANSFER_FIELD_QVAPOR : TRANSFER_FIELD_TEMPERATURE);
        assert_true(h->lo == lo && h->hi == hi);
        uint32_t count[TRANSFER_HISTOGRAM_BINS];
        uint64_t below, above;
        size_t n = grid3_count(&fv.grid);
        count_here(field, n, lo, hi, count, &below, &above);
        assert_memory_equal(h->count, count, sizeof(count));
        assert_true(h->below == below && h->above == above && h->total == n);
        /* Not all in one bin: a histogram with a shape. */
        int used = 0;
        for (int b = 0; b < TRANSFER_HISTOGRAM_BINS; b++)
            used += count[b] > 0;
        assert_true(used >= 8);
        field_volume_finish(&fv);
        wrf_close(w);
        ext_volume_finish(&vol);
        player_destroy(p);
    }
}

/* The editor's bars count the field of the layer it edits: layer 2's temperature once the
 * look says layer 2 is the edited one, layer 1's water vapour before and when the edited index
 * names no layer. */
static void test_histogram_of_edited_layer(void **state)
{
    static struct config cfg;
    char path[1024];
    snprintf(path, sizeof(path), "%s/configs/katrina.cfg", ANVIL_SOURCE_DIR);
    const char *sets[] = {"data.step=2"};
    test_config_file(&cfg, path, sets, 1);
    log_set_level(LOG_ERROR);
    struct player *p = player_create(&cfg, &(struct player_desc){.still = true, .histogram = true});
    log_set_level(LOG_INFO);
    assert_non_null(p);
    struct ext_volume first;
    assert_true(player_take_first(p, &first));
    struct look look;
    look_from_config(&cfg, &look);
    look.layer_count = 2;
    look.layers[0] =
        (struct transfer_layer){.enabled = true, .mode = TRANSFER_LAYER_EMIT, .opacity = 0.02};
    transfer_defaults(&look.layers[0].tf, TRANSFER_FIELD_QVAPOR);
    look.layers[1] = look.layers[0];
    transfer_defaults(&look.layers[1].tf, TRANSFER_FIELD_TEMPERATURE);
    const int edited[] = {1, 0, 7};
    const enum transfer_field want[] = {TRANSFER_FIELD_TEMPERATURE, TRANSFER_FIELD_QVAPOR,
                                        TRANSFER_FIELD_QVAPOR};
    for (int i = 0; i < 3; i++) {
        look.edited = edited[i];
        player_set_look(p, &look);
        int shown = -1;
        log_set_level(LOG_ERROR);
        const struct ext_volume *v = player_poll(p, 2, &shown);
        log_set_level(LOG_INFO);
        assert_non_null(v);
        assert_int_equal(shown, 2);
        assert_non_null(v->histogram);
        const struct transfer_histogram *h = v->histogram;
        assert_int_equal(h->field, want[i]);
        struct transfer_function tf;
        transfer_defaults(&tf, want[i]);
        assert_true(h->lo == tf.lo && h->hi == tf.hi);
        /* Water vapour's bars are the first step's (no layers: the editor's default function). */
        bool same = memcmp(h->count, first.histogram->count, sizeof(h->count)) == 0;
        assert_true(same == (want[i] == TRANSFER_FIELD_QVAPOR));
    }
    ext_volume_finish(&first);
    player_destroy(p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_katrina_grid_point),
        cmocka_unit_test(test_lambert_wind_turned),
        cmocka_unit_test(test_point_is_the_volume),
        cmocka_unit_test(test_wind_direction),
        cmocka_unit_test(test_first_visible),
        cmocka_unit_test(test_sample_fields),
        cmocka_unit_test(test_height_level_pressure_is_the_files),
        cmocka_unit_test(test_histogram_counts),
        cmocka_unit_test(test_histogram_of_edited_layer),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
