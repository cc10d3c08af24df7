/* Temperature and wind speed for classic transfer-function mode: hand-computed values on a
 * small WRF file made here (staggered U, V, W), the synthetic writer's wind, Katrina, and the
 * transfer function's field names. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <netcdf.h>

#include "testutil.h"

#include "common/log.h"
#include "data/derived.h"
#include "data/synth.h"
#include "data/wrf.h"
#include "data/wrf_write.h"
#include "optics/transfer.h"

#define NX 3
#define NY 2
#define NZ 2
#define CHECK(x) assert_int_equal((x), NC_NOERR)

enum { WITH_WIND = 1, WITH_W = 2, BAD_U = 4 };

/* One time on a 3 x 2 x 2 grid, staggered levels every 100 m (mass levels at 50 and 150 m, so
 * the regular height grid is the identity).  At mass point (i, j, k):
 *   P = 100 i + 200 j, PB = 85200 - 10000 k, T = 5 + k;
 * on the staggered points (i_s, j_s, k_s the staggered index):
 *   U = 2 i_s + 10 k + j, V = 3 j_s + i, W = k_s + 0.1 i. */
static const char *make_file(const char *name, unsigned what)
{
    char path[512];
    snprintf(path, sizeof(path), "%s", test_tmp_path(name));
    int nc, dt, dx, dy, dz, dzs, dxs, dys;
    CHECK(nc_create(path, NC_CLOBBER | NC_NETCDF4, &nc));
    CHECK(nc_def_dim(nc, "Time", NC_UNLIMITED, &dt));
    CHECK(nc_def_dim(nc, "west_east", NX, &dx));
    CHECK(nc_def_dim(nc, "south_north", NY, &dy));
    CHECK(nc_def_dim(nc, "bottom_top", NZ, &dz));
    CHECK(nc_def_dim(nc, "bottom_top_stag", NZ + 1, &dzs));
    CHECK(nc_def_dim(nc, "west_east_stag", NX + 1, &dxs));
    CHECK(nc_def_dim(nc, "south_north_stag", NY + 1, &dys));
    float dxy = 1000.0f;
    CHECK(nc_put_att_float(nc, NC_GLOBAL, "DX", NC_FLOAT, 1, &dxy));
    CHECK(nc_put_att_float(nc, NC_GLOBAL, "DY", NC_FLOAT, 1, &dxy));
    int d4[4] = {dt, dz, dy, dx}, d4s[4] = {dt, dzs, dy, dx};
    int du[4] = {dt, dz, dy, (what & BAD_U) ? dx : dxs}, dv[4] = {dt, dz, dys, dx};
    int vp, vpb, vt, vph, vphb, vu = -1, vv = -1, vw = -1;
    CHECK(nc_def_var(nc, "P", NC_FLOAT, 4, d4, &vp));
    CHECK(nc_def_var(nc, "PB", NC_FLOAT, 4, d4, &vpb));
    CHECK(nc_def_var(nc, "T", NC_FLOAT, 4, d4, &vt));
    CHECK(nc_def_var(nc, "PH", NC_FLOAT, 4, d4s, &vph));
    CHECK(nc_def_var(nc, "PHB", NC_FLOAT, 4, d4s, &vphb));
    if (what & WITH_WIND) {
        CHECK(nc_def_var(nc, "U", NC_FLOAT, 4, du, &vu));
        CHECK(nc_def_var(nc, "V", NC_FLOAT, 4, dv, &vv));
    }
    if (what & WITH_W)
        CHECK(nc_def_var(nc, "W", NC_FLOAT, 4, d4s, &vw));
    CHECK(nc_enddef(nc));

    float p[NZ][NY][NX], pb[NZ][NY][NX], t[NZ][NY][NX];
    float ph[NZ + 1][NY][NX], phb[NZ + 1][NY][NX], w[NZ + 1][NY][NX];
    float u[NZ][NY][NX + 1], v[NZ][NY + 1][NX];
    for (int k = 0; k <= NZ; k++)
        for (int j = 0; j <= NY; j++)
            for (int i = 0; i <= NX; i++) {
                if (k < NZ && j < NY && i < NX) {
                    p[k][j][i] = 100.0f * i + 200.0f * j;
                    pb[k][j][i] = 85200.0f - 10000.0f * k;
                    t[k][j][i] = 5.0f + k;
                }
                if (j < NY && i < NX) {
                    ph[k][j][i] = 0.0f;
                    phb[k][j][i] = 100.0f * k * 9.81f;
                    w[k][j][i] = k + 0.1f * i;
                }
                if (k < NZ && j < NY)
                    u[k][j][i] = 2.0f * i + 10.0f * k + j;
                if (k < NZ && i < NX)
                    v[k][j][i] = 3.0f * j + i;
            }
    size_t s[4] = {0, 0, 0, 0};
    CHECK(nc_put_vara_float(nc, vp, s, (size_t[]){1, NZ, NY, NX}, &p[0][0][0]));
    CHECK(nc_put_vara_float(nc, vpb, s, (size_t[]){1, NZ, NY, NX}, &pb[0][0][0]));
    CHECK(nc_put_vara_float(nc, vt, s, (size_t[]){1, NZ, NY, NX}, &t[0][0][0]));
    CHECK(nc_put_vara_float(nc, vph, s, (size_t[]){1, NZ + 1, NY, NX}, &ph[0][0][0]));
    CHECK(nc_put_vara_float(nc, vphb, s, (size_t[]){1, NZ + 1, NY, NX}, &phb[0][0][0]));
    if (vu >= 0) {
        /* BAD_U: U over west_east (the first NX values of each row). */
        float ub[NZ][NY][NX];
        for (int k = 0; k < NZ; k++)
            for (int j = 0; j < NY; j++)
                for (int i = 0; i < NX; i++)
                    ub[k][j][i] = u[k][j][i];
        CHECK(nc_put_vara_float(nc, vu, s, (size_t[]){1, NZ, NY, (what & BAD_U) ? NX : NX + 1},
                                (what & BAD_U) ? &ub[0][0][0] : &u[0][0][0]));
        CHECK(nc_put_vara_float(nc, vv, s, (size_t[]){1, NZ, NY + 1, NX}, &v[0][0][0]));
    }
    if (vw >= 0)
        CHECK(nc_put_vara_float(nc, vw, s, (size_t[]){1, NZ + 1, NY, NX}, &w[0][0][0]));
    CHECK(nc_close(nc));
    return test_tmp_path(name);
}

static bool read_one(const char *path, int stride_x, struct field_volume *out,
                     struct wrf_meta *meta)
{
    struct wrf *w = wrf_open(&path, 1, 0.0);
    assert_non_null(w);
    if (meta)
        *meta = *wrf_get_meta(w);
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    d.temperature = true;
    d.wind = true;
    d.stride[0] = stride_x;
    bool ok = wrf_read_step(w, 0, &d, out, NULL);
    if (meta) /* the arrays go with the reader */
        meta->xlat = meta->xlong = meta->hgt = meta->landmask = meta->lu_index = NULL;
    wrf_close(w);
    return ok;
}

static void test_temperature_by_hand(void **state)
{
    struct field_volume v;
    assert_true(read_one(make_file("tw.nc", WITH_WIND | WITH_W), 1, &v, NULL));
    assert_non_null(v.temperature);
    assert_int_equal(v.grid.n[2], NZ);
    /* (1, 1, 0): p = 300 + 85200 = 85500 Pa, theta = 305 K:
     * 305 (0.855)^(287 / 1004.5) = 291.6497 K. */
    assert_float_equal(v.temperature[grid3_index(&v.grid, 1, 1, 0)], 291.6497, 2e-3);
    /* (1, 1, 1): p = 300 + 75200 = 75500 Pa, theta = 306 K: 282.3899 K. */
    assert_float_equal(v.temperature[grid3_index(&v.grid, 1, 1, 1)], 282.3899, 2e-3);
    /* (0, 0, 0): p = 85200 Pa, theta = 305 K. */
    double t0 = 305.0 * pow(85200.0 / 100000.0, 287.0 / 1004.5);
    assert_float_equal(v.temperature[grid3_index(&v.grid, 0, 0, 0)], t0, 2e-3);
    assert_float_equal(optics_wrf_temperature(85500.0, 305.0), 291.6497, 1e-3);
    field_volume_finish(&v);
}

static void test_wind_by_hand(void **state)
{
    struct field_volume v;
    assert_true(read_one(make_file("tw.nc", WITH_WIND | WITH_W), 1, &v, NULL));
    assert_non_null(v.wind);
    /* (1, 1, 1): U faces 1 and 2: (13 + 15) / 2 = 14; V faces 1 and 2: (4 + 7) / 2 = 5.5;
     * W levels 1 and 2: (1.1 + 2.1) / 2 = 1.6; |(14, 5.5, 1.6)| = sqrt(228.81) = 15.12647. */
    assert_float_equal(v.wind[grid3_index(&v.grid, 1, 1, 1)], 15.12647, 1e-4);
    /* (0, 0, 0): U (0 + 2) / 2 = 1; V (0 + 3) / 2 = 1.5; W (0 + 1) / 2 = 0.5: sqrt(3.5). */
    assert_float_equal(v.wind[grid3_index(&v.grid, 0, 0, 0)], sqrt(3.5), 1e-5);
    field_volume_finish(&v);

    /* Without W: the horizontal speed, sqrt(14^2 + 5.5^2) = 15.04161. */
    assert_true(read_one(make_file("tw2.nc", WITH_WIND), 1, &v, NULL));
    assert_float_equal(v.wind[grid3_index(&v.grid, 1, 1, 1)], 15.04161, 1e-4);
    field_volume_finish(&v);

    /* Every second column: output column 1 is the file's column 2, U faces 2 and 3:
     * (15 + 17) / 2 = 16; V (5 + 8) / 2 = 6.5; W (1.2 + 2.2) / 2 = 1.7: sqrt(301.14). */
    assert_true(read_one(make_file("tw.nc", WITH_WIND | WITH_W), 2, &v, NULL));
    assert_int_equal(v.grid.n[0], 2);
    assert_float_equal(v.wind[grid3_index(&v.grid, 1, 1, 1)], 17.35339, 1e-4);
    field_volume_finish(&v);
}

static void test_wind_unavailable(void **state)
{
    struct field_volume v;
    struct wrf_meta m;
    unsigned warns = log_warn_count();
    assert_true(read_one(make_file("nowind.nc", 0), 1, &v, &m));
    assert_false(m.has_wind);
    assert_null(v.wind);
    assert_non_null(v.temperature); /* the rest of the step is still there */
    assert_non_null(v.rho_air);
    assert_true(log_warn_count() > warns);
    field_volume_finish(&v);

    /* U over west_east instead of west_east_stag: the file opens, the wind is unavailable. */
    warns = log_warn_count();
    unsigned errors = log_error_count();
    assert_true(read_one(make_file("badu.nc", WITH_WIND | WITH_W | BAD_U), 1, &v, &m));
    assert_false(m.has_wind);
    assert_null(v.wind);
    assert_true(log_warn_count() >= warns + 2);
    assert_int_equal(log_error_count(), errors);
    field_volume_finish(&v);
}

/* anvil synth's file: U, V, W of wrf_synth_wind, T of the standard atmosphere. */
static void test_synth_wind_and_temperature(void **state)
{
    char path[512];
    snprintf(path, sizeof(path), "%s", test_tmp_path("synthw.nc"));
    struct synth_desc sd = {
        .kind = SYNTH_STORM, .n = {20, 16, 10}, .extent_m = {40000.0, 32000.0, 15000.0}, .seed = 3};
    struct field_volume in;
    assert_true(synth_storm_fields(&sd, &in));
    test_write_wrf_step(path, &in);
    const char *p = path;
    struct wrf *w = wrf_open(&p, 1, 0.0);
    assert_non_null(w);
    assert_true(wrf_get_meta(w)->has_wind);
    assert_true(wrf_get_meta(w)->has_w);
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    d.temperature = true;
    d.wind = true;
    struct field_volume out;
    assert_true(wrf_read_step(w, 0, &d, &out, NULL));
    const struct grid3 *g = &in.grid;
    const int at[3][3] = {{3, 4, 2}, {10, 8, 5}, {17, 12, 8}};
    for (int c = 0; c < 3; c++) {
        int i = at[c][0], j = at[c][1], k = at[c][2];
        double dx = g->spacing[0], dy = g->spacing[1], dz = g->spacing[2];
        double zm = g->origin[2] + (k + 0.5) * dz, u0, u1, v0, v1, w0, w1, a, b;
        wrf_synth_wind(g, i * dx, (j + 0.5) * dy, zm, &u0, &a, &b);
        wrf_synth_wind(g, (i + 1) * dx, (j + 0.5) * dy, zm, &u1, &a, &b);
        wrf_synth_wind(g, (i + 0.5) * dx, j * dy, zm, &a, &v0, &b);
        wrf_synth_wind(g, (i + 0.5) * dx, (j + 1) * dy, zm, &a, &v1, &b);
        wrf_synth_wind(g, (i + 0.5) * dx, (j + 0.5) * dy, g->origin[2] + k * dz, &a, &b, &w0);
        wrf_synth_wind(g, (i + 0.5) * dx, (j + 0.5) * dy, g->origin[2] + (k + 1) * dz, &a, &b,
                       &w1);
        double um = 0.5 * (u0 + u1), vm = 0.5 * (v0 + v1), wm = 0.5 * (w0 + w1);
        double want = sqrt(um * um + vm * vm + wm * wm);
        size_t idx = grid3_index(&out.grid, i, j, k);
        assert_float_equal(out.wind[idx], want, 1e-4 * want + 1e-5);
        double temp, pres;
        wrf_std_atmosphere(zm, &temp, &pres);
        assert_float_equal(out.temperature[idx], temp, 0.05);
    }
    field_volume_finish(&out);
    field_volume_finish(&in);
    wrf_close(w);
}

/* The vertical velocity and vorticity of anvil synth's wind: inside the radius of maximum wind
 * its vortex turns as a solid body at Omega = 30 m/s decay(z) / rmax, so zeta = 2 Omega (the
 * uniform westerly adds none); W is the mean of its two staggered levels.  Read with a stride
 * too (the spacing between kept columns), and through derived_field from u and v alone (what
 * CM1, CF and Isabel give). */
static void test_vorticity_solid_body(void **state)
{
    (void)state;
    char path[512];
    snprintf(path, sizeof(path), "%s", test_tmp_path("synthz.nc"));
    struct synth_desc sd = {
        .kind = SYNTH_STORM, .n = {40, 40, 8}, .extent_m = {80000.0, 80000.0, 16000.0}, .seed = 5};
    struct field_volume in;
    assert_true(synth_storm_fields(&sd, &in));
    test_write_wrf_step(path, &in);
    const char *p = path;
    struct wrf *w = wrf_open(&p, 1, 0.0);
    assert_non_null(w);
    const struct grid3 *g = &in.grid;
    double rmax = 0.15 * 80000.0;
    for (int stride = 1; stride <= 2; stride++) {
        struct wrf_desc d;
        wrf_desc_defaults(&d);
        d.stride[0] = d.stride[1] = stride;
        struct field_volume out;
        assert_true(wrf_read_step(w, 0, &d, &out, NULL));
        assert_null(out.vorticity); /* not asked */
        assert_false(derived_field_available(&out, TRANSFER_FIELD_VORTICITY));
        field_volume_finish(&out);
        assert_null(out.level_z);
        d.wind_components = true;
        d.level_heights = true;
        assert_true(wrf_read_step(w, 0, &d, &out, NULL));
        /* The mass levels' heights per kept column: the synthetic file's levels are flat, at
         * the voxel centres. */
        assert_non_null(out.level_z);
        assert_int_equal(out.level_count, g->n[2]);
        for (int k = 0; k < g->n[2]; k++)
            assert_float_equal(out.level_z[grid3_index(&out.grid, 3, 5, k)],
                               g->origin[2] + (k + 0.5) * g->spacing[2], 0.05);
        assert_non_null(out.vorticity);
        assert_non_null(out.w);
        assert_non_null(out.wind);
        assert_true(derived_field_available(&out, TRANSFER_FIELD_VORTICITY));
        assert_true(derived_field_available(&out, TRANSFER_FIELD_W));
        size_t n = grid3_count(&out.grid);
        float *zeta = malloc(n * sizeof(float)), *fromuv = malloc(n * sizeof(float));
        float *wz = malloc(n * sizeof(float));
        assert_non_null(zeta);
        assert_non_null(fromuv);
        assert_non_null(wz);
        derived_field(&out, TRANSFER_FIELD_VORTICITY, zeta);
        derived_field(&out, TRANSFER_FIELD_W, wz);
        float *own = out.vorticity;
        out.vorticity = NULL;
        derived_field(&out, TRANSFER_FIELD_VORTICITY, fromuv);
        out.vorticity = own;
        int checked = 0;
        for (int k = 0; k < out.grid.n[2]; k++)
            for (int j = 0; j < out.grid.n[1]; j++)
                for (int i = 0; i < out.grid.n[0]; i++) {
                    /* Kept column i is the file's mass column i * stride. */
                    double x = (i * stride + 0.5) * g->spacing[0];
                    double y = (j * stride + 0.5) * g->spacing[1];
                    double z = g->origin[2] + (k + 0.5) * g->spacing[2];
                    double r = hypot(x - 40000.0, y - 40000.0);
                    size_t idx = grid3_index(&out.grid, i, j, k);
                    double w0, w1, a, b;
                    wrf_synth_wind(g, x, y, z - 0.5 * g->spacing[2], &a, &b, &w0);
                    wrf_synth_wind(g, x, y, z + 0.5 * g->spacing[2], &a, &b, &w1);
                    assert_float_equal(wz[idx], 0.5 * (w0 + w1), 1e-4);
                    /* Every wind the differences take inside the core: the neighbours one
                     * kept spacing away, their faces half a file spacing beyond. */
                    if (r > rmax - M_SQRT2 * out.grid.spacing[0] - 0.5 * g->spacing[0])
                        continue;
                    double omega = 30.0 * fmax(0.0, 1.0 - z / 15000.0) / rmax;
                    assert_float_equal(zeta[idx], 2.0 * omega, 1e-3 * 2.0 * omega + 1e-7);
                    assert_float_equal(fromuv[idx], zeta[idx], 1e-7);
                    checked++;
                }
        assert_true(checked > 20);
        /* Outside the core the Rankine vortex is irrotational (v r constant): zeta is small
         * against 2 Omega away from the core's edge and the domain's. */
        size_t far = grid3_index(&out.grid, out.grid.n[0] / 2 + 14 / stride,
                                 out.grid.n[1] / 2, 0);
        double omega0 = 30.0 * (1.0 - (g->origin[2] + 0.5 * g->spacing[2]) / 15000.0) / rmax;
        assert_true(fabs(zeta[far]) < 0.1 * 2.0 * omega0);
        free(zeta);
        free(fromuv);
        free(wz);
        field_volume_finish(&out);
    }
    field_volume_finish(&in);
    wrf_close(w);
}

/* On a map of scale factor m, distances on the ground are the map's divided by m: a solid body
 * turning at Omega in ground coordinates (u = -Omega y, v = Omega x, x = i dx / m) has
 * zeta = 2 Omega, and differences on the map's grid alone give 2 Omega / m. */
static void test_vorticity_on_a_map(void **state)
{
    (void)state;
    enum { W = 7, H = 5 };
    const double omega = 1e-3, dx = 3000.0, dy = 2000.0, m = 1.25;
    float u[W * H], v[W * H], map[W * H], out[W * H];
    for (int j = 0; j < H; j++)
        for (int i = 0; i < W; i++) {
            u[j * W + i] = (float)(-omega * (j * dy / m));
            v[j * W + i] = (float)(omega * (i * dx / m));
            map[j * W + i] = (float)m;
        }
    derived_vorticity_plane(u, v, map, W, H, dx, dy, out);
    for (int c = 0; c < W * H; c++)
        assert_float_equal(out[c], 2.0 * omega, 1e-9);
    derived_vorticity_plane(u, v, NULL, W, H, dx, dy, out);
    for (int c = 0; c < W * H; c++)
        assert_float_equal(out[c], 2.0 * omega / m, 1e-9);
}

/* MAPFAC_M added to anvil synth's file, m = 1 + 0.01 i + 0.02 j over the file's mass columns:
 * the reader's vorticity is the map form over its kept columns' factors (with a stride, the
 * file's columns i * stride), and a factor that is not one (NaN) leaves the map's grid, with
 * one warning. */
static void test_vorticity_map_factors_read(void **state)
{
    (void)state;
    char path[512];
    snprintf(path, sizeof(path), "%s", test_tmp_path("synthm.nc"));
    struct synth_desc sd = {
        .kind = SYNTH_STORM, .n = {24, 20, 6}, .extent_m = {48000.0, 40000.0, 12000.0}, .seed = 3};
    struct field_volume in;
    assert_true(synth_storm_fields(&sd, &in));
    const int nx = sd.n[0], ny = sd.n[1];
    for (int bad = 0; bad < 2; bad++) {
        test_write_wrf_step(path, &in);
        int nc, dims[3], var;
        CHECK(nc_open(path, NC_WRITE, &nc));
        CHECK(nc_redef(nc));
        CHECK(nc_inq_dimid(nc, "Time", &dims[0]));
        CHECK(nc_inq_dimid(nc, "south_north", &dims[1]));
        CHECK(nc_inq_dimid(nc, "west_east", &dims[2]));
        CHECK(nc_def_var(nc, "MAPFAC_M", NC_FLOAT, 3, dims, &var));
        CHECK(nc_enddef(nc));
        float *mf = malloc((size_t)nx * ny * sizeof(float));
        assert_non_null(mf);
        for (int j = 0; j < ny; j++)
            for (int i = 0; i < nx; i++)
                mf[j * nx + i] = bad && i == 3 && j == 2 ? NAN : 1.0f + 0.01f * i + 0.02f * j;
        CHECK(nc_put_var_float(nc, var, mf));
        CHECK(nc_close(nc));
        const char *p = path;
        log_set_level(LOG_ERROR);
        struct wrf *w = wrf_open(&p, 1, 0.0);
        log_set_level(LOG_INFO);
        assert_non_null(w);
        assert_true((wrf_get_meta(w)->mapfac_m == NULL) == (bad == 1));
        for (int stride = 1; stride <= 2; stride++) {
            struct wrf_desc d;
            wrf_desc_defaults(&d);
            d.stride[0] = d.stride[1] = stride;
            d.wind_components = true;
            struct field_volume out;
            assert_true(wrf_read_step(w, 0, &d, &out, NULL));
            const struct grid3 *g = &out.grid;
            size_t plane = (size_t)g->n[0] * g->n[1];
            float *kept = malloc(plane * sizeof(float)), *want = malloc(plane * sizeof(float));
            assert_non_null(kept);
            assert_non_null(want);
            for (int j = 0; j < g->n[1]; j++)
                for (int i = 0; i < g->n[0]; i++)
                    kept[j * g->n[0] + i] = mf[(j * stride) * nx + i * stride];
            /* The synthetic file's levels are flat at the voxel centres: its model levels are
             * the height grid's, so the differences on a level are those on a grid plane. */
            double most = 0.0;
            for (int k = 0; k < g->n[2]; k++) {
                derived_vorticity_plane(out.u + k * plane, out.v + k * plane, bad ? NULL : kept,
                                        g->n[0], g->n[1], in.grid.spacing[0] * stride,
                                        in.grid.spacing[1] * stride, want);
                for (size_t c = 0; c < plane; c++) {
                    assert_float_equal(out.vorticity[k * plane + c], want[c],
                                       1e-4 * fabs(want[c]) + 1e-8);
                    most = fmax(most, fabs(want[c]));
                }
            }
            assert_true(most > 1e-4); /* a vortex, not a calm */
            free(kept);
            free(want);
            field_volume_finish(&out);
        }
        free(mf);
        wrf_close(w);
    }
    field_volume_finish(&in);
}

/* Katrina has U, V, W and T: every voxel finite and plausible; column (10, 10) near the
 * ground from its P, PB, T (ncdump): 302.289789 (99571.77 / 1e5)^(287 / 1004.5). */
static void test_katrina(void **state)
{
    const char *path = test_shared_data("wrf/katrina_2005_mercator_wsm3.nc");
    struct wrf *w = wrf_open(&path, 1, 0.0);
    assert_non_null(w);
    assert_true(wrf_get_meta(w)->has_wind);
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    d.temperature = true;
    d.wind = true;
    struct field_volume v;
    assert_true(wrf_read_step(w, 0, &d, &v, NULL));
    size_t n = grid3_count(&v.grid);
    double wmax = 0.0;
    for (size_t i = 0; i < n; i++) {
        assert_true(isfinite(v.temperature[i]) && v.temperature[i] > 180.0f &&
                    v.temperature[i] < 320.0f);
        assert_true(isfinite(v.wind[i]) && v.wind[i] >= 0.0f && v.wind[i] < 120.0f);
        wmax = fmax(wmax, v.wind[i]);
    }
    assert_true(wmax > 20.0); /* a hurricane */
    field_volume_finish(&v);
    d.levels = 1000;
    d.top_m = 10000.0; /* the lowest 10 m levels clamp to the first mass level */
    assert_true(wrf_read_step(w, 0, &d, &v, NULL));
    assert_float_equal(v.temperature[grid3_index(&v.grid, 10, 10, 0)], 301.91937, 0.02);
    field_volume_finish(&v);
    wrf_close(w);
}

/* The derived fields against numbers worked by hand from their formulas: theta at 850 hPa and
 * 288.15 K is 288.15 (1000/850)^(287/1004.5) = 301.85 K; at 20 C and 1000 hPa the saturation
 * vapour pressure is 23.37 hPa (Bolton eq. 10), so q = 0.622 e/(p - e) with e = 11.685 hPa
 * (half of it) is 50 %; pressure from rho and T by the gas law. */
static void test_derived_fields(void **state)
{
    (void)state;
    assert_float_equal(derived_theta(288.15, 85000.0), 301.845, 0.01);
    assert_float_equal(derived_theta(300.0, 100000.0), 300.0, 1e-9);
    double es = 611.2 * exp(17.67 * 20.0 / (293.15 - 29.65));
    assert_float_equal(es, 2337.0, 1.0);
    double e = 0.5 * es, q = 0.622 * e / (100000.0 - e);
    assert_float_equal(derived_rh(293.15, 100000.0, q), 50.0, 1e-6);
    assert_float_equal(derived_pressure(1.2, 290.0), 1.2 * 287.0 * 290.0, 1e-6);
    assert_true(isnan(derived_theta(-1.0, 1e5)) && isnan(derived_rh(290.0, 0.0, 0.01)));

    /* On a volume: per voxel, from the volume's temperature, density and QVAPOR. */
    struct field_volume fv = {0};
    fv.grid = (struct grid3){.n = {2, 1, 2}, .spacing = {1000, 1000, 1000}};
    float t[4] = {300.0f, 290.0f, 280.0f, 270.0f}, rho[4] = {1.1f, 1.1f, 0.9f, 0.9f};
    float qv[4] = {0.015f, 0.01f, 0.005f, 0.001f};
    fv.temperature = t;
    fv.rho_air = rho;
    fv.qvapor = qv;
    float out[4];
    derived_field(&fv, TRANSFER_FIELD_THETA, out);
    for (int i = 0; i < 4; i++)
        assert_float_equal(out[i], derived_theta(t[i], derived_pressure(rho[i], t[i])), 1e-3);
    assert_true(derived_field_available(&fv, TRANSFER_FIELD_RH));
    derived_field(&fv, TRANSFER_FIELD_RH, out);
    for (int i = 0; i < 4; i++)
        assert_float_equal(out[i], derived_rh(t[i], derived_pressure(rho[i], t[i]), qv[i]),
                           1e-3);
    fv.rho_air = NULL;
    assert_false(derived_field_available(&fv, TRANSFER_FIELD_THETA));
}

static void test_field_names(void **state)
{
    const char *names[] = {"qvapor",    "condensate", "temperature", "wind",
                           "theta",     "rh",         "w",           "vorticity"};
    assert_int_equal(TRANSFER_FIELD_COUNT, sizeof(names) / sizeof(names[0]));
    for (int f = 0; f < TRANSFER_FIELD_COUNT; f++) {
        enum transfer_field got;
        assert_true(transfer_field_from_name(names[f], &got));
        assert_int_equal(got, f);
        assert_string_equal(transfer_field_name((enum transfer_field)f), names[f]);
        struct transfer_function tf;
        transfer_defaults(&tf, (enum transfer_field)f);
        assert_true(transfer_valid(&tf, NULL, 0));
    }
    struct transfer_function tf;
    transfer_defaults(&tf, TRANSFER_FIELD_TEMPERATURE);
    assert_true(tf.lo < 273.15 && tf.hi > 288.15); /* freezing and the surface inside */
    char buf[32];
    transfer_format_value(TRANSFER_FIELD_TEMPERATURE, 273.15, buf, sizeof(buf));
    assert_string_equal(buf, "0.0 C");
    transfer_format_value(TRANSFER_FIELD_WIND, 60.0, buf, sizeof(buf));
    assert_string_equal(buf, "60 m/s");
    transfer_format_value(TRANSFER_FIELD_QVAPOR, 0.012, buf, sizeof(buf));
    assert_string_equal(buf, "12 g/kg");
}

int main(void)
{
    log_set_level(LOG_ERROR);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_temperature_by_hand),
        cmocka_unit_test(test_wind_by_hand),
        cmocka_unit_test(test_wind_unavailable),
        cmocka_unit_test(test_synth_wind_and_temperature),
        cmocka_unit_test(test_vorticity_solid_body),
        cmocka_unit_test(test_vorticity_on_a_map),
        cmocka_unit_test(test_vorticity_map_factors_read),
        cmocka_unit_test(test_katrina),
        cmocka_unit_test(test_field_names),
        cmocka_unit_test(test_derived_fields),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
