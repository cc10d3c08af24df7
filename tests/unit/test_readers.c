/* CM1 and CF NetCDF on height levels: the same storm as the WRF synth file (mass ratios exact,
 * extinction within the gas constants' difference), temperature from th and prs, wind from the
 * staggered components, time steps across files, unit conversions, missing species, and the
 * errors (wrong units, non-monotone heights, budget); the content predicates. */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <netcdf.h>

#include "common/log.h"
#include "data/cf.h"
#include "data/cm1.h"
#include "data/geo.h"
#include "data/hgrid_write.h"
#include "data/probe.h"
#include "data/source.h"
#include "data/synth.h"
#include "data/wrf_write.h"

#define NX 20
#define NY 16
#define NZ 12

static void storm(double time, struct field_volume *fv)
{
    struct synth_desc sd = {.kind = SYNTH_STORM, .seed = 3, .time = time,
                            .n = {NX, NY, NZ}, .extent_m = {30e3, 24e3, 15e3}};
    assert_true(synth_storm_fields(&sd, fv));
}

static const char *write_hgrid(const char *name, const struct hgrid_write_desc *d, int steps,
                               double t0)
{
    static char path[4][1024];
    static int slot;
    char *p = path[slot++ % 4];
    snprintf(p, 1024, "%s", test_tmp_path(name));
    struct hgrid_writer *w = NULL;
    for (int s = 0; s < steps; s++) {
        struct field_volume fv;
        storm(steps > 1 ? (double)s / (steps - 1) : 0.0, &fv);
        if (!w)
            w = hgrid_writer_create(p, &fv.grid, d);
        assert_non_null(w);
        assert_true(hgrid_writer_add(w, &fv, t0 + 600.0 * s));
        field_volume_finish(&fv);
    }
    assert_true(hgrid_writer_finish(w));
    return p;
}

static const char *write_wrf(const char *name, int steps)
{
    static char p[1024];
    snprintf(p, sizeof(p), "%s", test_tmp_path(name));
    struct wrf_write_desc wd = {.cen_lat = 25.0, .cen_lon = -89.0};
    struct wrf_writer *w = NULL;
    for (int s = 0; s < steps; s++) {
        struct field_volume fv;
        storm(steps > 1 ? (double)s / (steps - 1) : 0.0, &fv);
        if (!w)
            w = wrf_writer_create(p, &fv.grid, &wd);
        char date[32];
        snprintf(date, sizeof(date), "2000-01-01_00:%02d:00", 10 * s);
        assert_true(wrf_writer_add(w, &fv, date));
        field_volume_finish(&fv);
    }
    assert_true(wrf_writer_finish(w));
    return p;
}

static struct data_source *open_source(enum data_source_format f, const char **path)
{
    struct data_source_desc d;
    memset(&d, 0, sizeof(d));
    d.format = f;
    d.files = path;
    d.file_count = 1;
    wrf_desc_defaults(&d.wrf);
    d.wrf.memory_mb = 256;
    optics_params_defaults(&d.optics);
    species_select_defaults(&d.select);
    return data_source_open(&d);
}

/* The storm through CM1 and CF reads back as WRF's does: mass ratios bit for bit, extinction
 * within 2e-4 (CM1's dry-air gas constant is 287.04, WRF's 287: 1.4e-4 in density). */
static void test_same_storm(void **state)
{
    const char *wrf = write_wrf("same.wrf.nc", 1);
    struct hgrid_write_desc cm1d = {.kind = HGRID_CM1}, cfd = {.kind = HGRID_CF};
    const char *cm1 = write_hgrid("same.cm1.nc", &cm1d, 1, 0.0);
    const char *cf = write_hgrid("same.cf.nc", &cfd, 1, 0.0);
    struct data_source *sw = open_source(DATA_SOURCE_WRF, &wrf);
    struct data_source *sc = open_source(DATA_SOURCE_CM1, &cm1);
    struct data_source *sf = open_source(DATA_SOURCE_CF, &cf);
    assert_non_null(sw);
    assert_non_null(sc);
    assert_non_null(sf);
    struct field_volume fw, fc, ff;
    assert_true(data_source_load_fields(sw, 0, &fw));
    assert_true(data_source_load_fields(sc, 0, &fc));
    assert_true(data_source_load_fields(sf, 0, &ff));
    size_t n = grid3_count(&fw.grid);
    for (int a = 0; a < 3; a++) {
        assert_int_equal(fc.grid.n[a], fw.grid.n[a]);
        assert_float_equal(fc.grid.spacing[a], fw.grid.spacing[a], 1e-6 * fw.grid.spacing[a]);
        assert_float_equal(ff.grid.spacing[a], fw.grid.spacing[a], 1e-6 * fw.grid.spacing[a]);
        assert_float_equal(fc.grid.origin[a], 0.0, 1e-9);
    }
    for (int f = 0; f < SPECIES_COUNT; f++) {
        assert_non_null(fc.q[f]);
        assert_non_null(ff.q[f]);
        assert_memory_equal(fc.q[f], fw.q[f], n * sizeof(float));
        assert_memory_equal(ff.q[f], fw.q[f], n * sizeof(float));
    }
    assert_non_null(fc.rho_air); /* from prs and th */
    assert_non_null(ff.rho_air); /* from air_pressure and air_temperature */
    double worst = 0.0;
    for (size_t i = 0; i < n; i++)
        worst = fmax(worst, fabs(fc.rho_air[i] / fw.rho_air[i] - 1.0));
    assert_true(worst < 2e-4);
    assert_true(worst > 1e-5); /* the constants do differ: the comparison can see density */

    struct ext_volume ew, ec, ef;
    assert_true(data_source_load(sw, 0, &ew, NULL, NULL));
    assert_true(data_source_load(sc, 0, &ec, NULL, NULL));
    assert_true(data_source_load(sf, 0, &ef, NULL, NULL));
    double max_beta = ext_volume_max_beta(&ew), dc = 0.0, df = 0.0;
    assert_true(max_beta > 1e-4);
    for (size_t i = 0; i < 2 * n; i++) {
        double ref = ew.beta[i];
        dc = fmax(dc, fabs(ec.beta[i] - ref) / fmax(ref, 1e-3 * max_beta));
        df = fmax(df, fabs(ef.beta[i] - ref) / fmax(ref, 1e-3 * max_beta));
    }
    assert_true(dc < 2e-4);
    assert_true(df < 2e-4);
    ext_volume_finish(&ew);
    ext_volume_finish(&ec);
    ext_volume_finish(&ef);
    field_volume_finish(&fw);
    field_volume_finish(&fc);
    field_volume_finish(&ff);
    data_source_close(sw);
    data_source_close(sc);
    data_source_close(sf);
}

/* Temperature from th and prs (Poisson's equation) and wind speed from the staggered u, v, w
 * against what the writer put there. */
static void test_cm1_temperature_wind(void **state)
{
    struct hgrid_write_desc d = {.kind = HGRID_CM1};
    const char *p = write_hgrid("tw.cm1.nc", &d, 1, 0.0);
    struct hgrid *h = cm1_open(&p, 1, 256);
    assert_non_null(h);
    struct hgrid_desc hd = {.temperature = true, .wind = true, .qvapor = true};
    struct field_volume fv;
    assert_true(hgrid_read_step(h, 0, &hd, &fv, NULL));
    assert_non_null(fv.temperature);
    assert_non_null(fv.wind);
    assert_non_null(fv.qvapor);
    const struct grid3 *g = &fv.grid;
    for (int k = 0; k < NZ; k++) {
        double z = (k + 0.5) * g->spacing[2], t, pr;
        wrf_std_atmosphere(z, &t, &pr);
        assert_float_equal(fv.temperature[grid3_index(g, 3, 4, k)], t, 1e-2);
        assert_float_equal(fv.qvapor[grid3_index(g, 3, 4, k)], 0.01 * exp(-z / 2500.0), 1e-7);
    }
    /* Wind: the mean of the two faces around a mass point, as the writer's analytic wind. */
    int i = 7, j = 5, k = 4;
    double x0 = i * g->spacing[0], x1 = (i + 1) * g->spacing[0];
    double yc = (j + 0.5) * g->spacing[1], y0 = j * g->spacing[1], y1 = (j + 1) * g->spacing[1];
    double xc = (i + 0.5) * g->spacing[0], zc = (k + 0.5) * g->spacing[2];
    double ua, ub, va, vb, wa, wb, dummy1, dummy2;
    wrf_synth_wind(g, x0, yc, zc, &ua, &dummy1, &dummy2);
    wrf_synth_wind(g, x1, yc, zc, &ub, &dummy1, &dummy2);
    wrf_synth_wind(g, xc, y0, zc, &dummy1, &va, &dummy2);
    wrf_synth_wind(g, xc, y1, zc, &dummy1, &vb, &dummy2);
    wrf_synth_wind(g, xc, yc, k * g->spacing[2], &dummy1, &dummy2, &wa);
    wrf_synth_wind(g, xc, yc, (k + 1) * g->spacing[2], &dummy1, &dummy2, &wb);
    double u = 0.5 * (ua + ub), v = 0.5 * (va + vb), w = 0.5 * (wa + wb);
    double speed = sqrt(u * u + v * v + w * w);
    assert_true(speed > 1.0);
    assert_float_equal(fv.wind[grid3_index(g, i, j, k)], speed, 1e-4 * speed);
    assert_null(fv.u); /* the components only when asked for */
    assert_null(fv.v);
    assert_null(fv.w);
    field_volume_finish(&fv);

    /* Asked for: u, v, w on the mass points, and the probe's speed and direction from them. */
    hd.wind_components = true;
    assert_true(hgrid_read_step(h, 0, &hd, &fv, NULL));
    assert_non_null(fv.u);
    assert_non_null(fv.v);
    assert_non_null(fv.w);
    size_t idx = grid3_index(g, i, j, k);
    assert_float_equal(fv.u[idx], u, 1e-4 * speed);
    assert_float_equal(fv.v[idx], v, 1e-4 * speed);
    assert_float_equal(fv.w[idx], w, 1e-4 * speed + 1e-6);
    assert_float_equal(fv.wind[idx], speed, 1e-4 * speed);
    struct probe_sample ps;
    double at[3] = {xc, yc, zc}, s, from, s_want, from_want;
    assert_true(probe_sample_fields(&fv, at, &ps));
    assert_true(ps.has_wind);
    assert_true(ps.wind_earth_relative);
    assert_true(ps.has_w);
    probe_wind(ps.u, ps.v, &s, &from);
    probe_wind(u, v, &s_want, &from_want);
    assert_float_equal(s, s_want, 1e-4 * speed);
    assert_float_equal(from, from_want, 0.01);
    assert_float_equal(ps.w, w, 1e-4 * speed + 1e-6);
    field_volume_finish(&fv);
    hgrid_close(h);
}

/* CF's eastward_wind, northward_wind and upward_air_velocity through the data source: kept
 * only when the description asks (the probe), read as the speed alone otherwise. */
static void test_cf_wind_components(void **state)
{
    struct hgrid_write_desc d = {.kind = HGRID_CF};
    const char *p = write_hgrid("wc.cf.nc", &d, 1, 0.0);
    struct data_source_desc sd;
    memset(&sd, 0, sizeof(sd));
    sd.format = DATA_SOURCE_CF;
    sd.files = &p;
    sd.file_count = 1;
    wrf_desc_defaults(&sd.wrf);
    struct data_source *src = data_source_open(&sd);
    assert_non_null(src);
    struct field_volume fv;
    assert_true(data_source_load_fields_extra(src, 0, false, true, &fv));
    assert_non_null(fv.wind);
    assert_null(fv.u);
    field_volume_finish(&fv);
    data_source_close(src);

    sd.wind_components = true;
    src = data_source_open(&sd);
    assert_non_null(src);
    assert_true(data_source_load_fields_extra(src, 0, false, true, &fv));
    assert_non_null(fv.u);
    assert_non_null(fv.v);
    assert_non_null(fv.w);
    const struct grid3 *g = &fv.grid;
    int i = 6, j = 9, k = 3;
    double xc = (i + 0.5) * g->spacing[0], yc = (j + 0.5) * g->spacing[1],
           zc = (k + 0.5) * g->spacing[2], u, v, w;
    wrf_synth_wind(g, xc, yc, zc, &u, &v, &w); /* CF's wind is on the mass points */
    size_t idx = grid3_index(g, i, j, k);
    assert_true(hypot(u, v) > 1.0);
    assert_float_equal(fv.u[idx], u, 1e-4);
    assert_float_equal(fv.v[idx], v, 1e-4);
    assert_float_equal(fv.w[idx], w, 1e-4);
    double speed = sqrt(u * u + v * v + w * w);
    assert_float_equal(fv.wind[idx], speed, 1e-4 * speed);
    field_volume_finish(&fv);
    /* Temperature alone: no wind read, so no components either. */
    assert_true(data_source_load_fields_extra(src, 0, true, false, &fv));
    assert_null(fv.wind);
    assert_null(fv.u);
    field_volume_finish(&fv);
    data_source_close(src);
}

/* Steps from several files are ordered by time; the same time twice is an error. */
static void test_times(void **state)
{
    struct hgrid_write_desc d = {.kind = HGRID_CM1};
    const char *late = write_hgrid("t-late.cm1.nc", &d, 2, 1200.0); /* 1200, 1800 s */
    const char *early = write_hgrid("t-early.cm1.nc", &d, 1, 0.0);
    const char *both[2] = {late, early};
    struct hgrid *h = cm1_open(both, 2, 256);
    assert_non_null(h);
    assert_int_equal(hgrid_step_count(h), 3);
    assert_float_equal(hgrid_step_seconds(h, 0), 0.0, 1e-9);
    assert_float_equal(hgrid_step_seconds(h, 1), 1200.0, 1e-9);
    assert_float_equal(hgrid_step_seconds(h, 2), 1800.0, 1e-9);
    assert_string_equal(hgrid_step_path(h, 0), early);
    assert_string_equal(hgrid_step_date(h, 0), ""); /* CM1 counts seconds, no date */
    hgrid_close(h);

    const char *again[2] = {early, early};
    unsigned errors = log_error_count();
    assert_null(cm1_open(again, 2, 256));
    assert_int_equal(log_error_count(), errors + 1);
    assert_non_null(strstr(log_last_error(), "both hold time 0"));

    /* CF: "seconds since" a date gives dates. */
    struct hgrid_write_desc cfd = {.kind = HGRID_CF, .start = "2005-08-28_12:00:00"};
    const char *cf = write_hgrid("t.cf.nc", &cfd, 2, 0.0);
    h = cf_open(&cf, 1, 256);
    assert_non_null(h);
    assert_string_equal(hgrid_step_date(h, 1), "2005-08-28_12:10:00");
    assert_float_equal(hgrid_step_seconds(h, 1), 600.0, 1e-9);
    hgrid_close(h);
}

/* Units, the sign and the order of the vertical axis change nothing of what is read. */
static void test_cf_variants(void **state)
{
    struct hgrid_write_desc base = {.kind = HGRID_CF};
    struct hgrid_write_desc other = {.kind = HGRID_CF, .coords_km = true, .g_per_kg = true,
                                     .pressure_hpa = true, .positive_down = true,
                                     .top_down = true};
    const char *a = write_hgrid("v-base.cf.nc", &base, 1, 0.0);
    const char *b = write_hgrid("v-other.cf.nc", &other, 1, 0.0);
    struct hgrid *ha = cf_open(&a, 1, 256), *hb = cf_open(&b, 1, 256);
    assert_non_null(ha);
    assert_non_null(hb);
    assert_true(hgrid_get_meta(hb)->reversed);
    assert_false(hgrid_get_meta(ha)->reversed);
    struct hgrid_desc hd = {.temperature = true};
    struct field_volume fa, fb;
    assert_true(hgrid_read_step(ha, 0, &hd, &fa, NULL));
    assert_true(hgrid_read_step(hb, 0, &hd, &fb, NULL));
    size_t n = grid3_count(&fa.grid);
    for (int ax = 0; ax < 3; ax++)
        assert_float_equal(fb.grid.spacing[ax], fa.grid.spacing[ax], 1e-6);
    for (int f = 0; f < SPECIES_COUNT; f++)
        for (size_t i = 0; i < n; i++)
            assert_float_equal(fb.q[f][i], fa.q[f][i], 1e-6 * fa.q[f][i] + 1e-12);
    for (size_t i = 0; i < n; i++) {
        assert_float_equal(fb.rho_air[i], fa.rho_air[i], 1e-5 * fa.rho_air[i]);
        assert_float_equal(fb.temperature[i], fa.temperature[i], 1e-3);
    }
    /* The lowest output level is the lowest height, whichever way the file stores it. */
    double t, p;
    wrf_std_atmosphere(0.5 * fa.grid.spacing[2], &t, &p);
    assert_float_equal(fb.temperature[0], t, 1e-2);
    field_volume_finish(&fa);
    field_volume_finish(&fb);
    hgrid_close(ha);
    hgrid_close(hb);
}

/* Missing species read as zero (NULL), with one note; the rest is read. */
static void test_missing_species(void **state)
{
    struct hgrid_write_desc d = {.kind = HGRID_CF,
                                 .omit = 1u << SPECIES_RAIN | 1u << SPECIES_GRAUPEL};
    const char *p = write_hgrid("missing.cf.nc", &d, 1, 0.0);
    log_set_level(LOG_INFO);
    unsigned warnings = log_warn_count();
    struct data_source *s = open_source(DATA_SOURCE_CF, &p);
    log_set_level(LOG_ERROR);
    assert_non_null(s);
    assert_int_equal(log_warn_count(), warnings);
    struct field_volume fv;
    assert_true(data_source_load_fields(s, 0, &fv));
    assert_null(fv.q[SPECIES_RAIN]);
    assert_null(fv.q[SPECIES_GRAUPEL]);
    assert_non_null(fv.q[SPECIES_CLOUD]);
    assert_non_null(fv.q[SPECIES_SNOW]);
    field_volume_finish(&fv);
    data_source_close(s);
}

static void set_text_att(const char *path, const char *var, const char *att, const char *value)
{
    int nc, id;
    assert_int_equal(nc_open(path, NC_WRITE, &nc), NC_NOERR);
    assert_int_equal(nc_inq_varid(nc, var, &id), NC_NOERR);
    assert_int_equal(nc_redef(nc), NC_NOERR);
    assert_int_equal(nc_put_att_text(nc, id, att, strlen(value), value), NC_NOERR);
    assert_int_equal(nc_close(nc), NC_NOERR);
}

static void test_errors(void **state)
{
    /* A unit that is not one of the quantity's: the variable and the unit named. */
    struct hgrid_write_desc d = {.kind = HGRID_CF};
    const char *p = write_hgrid("units.cf.nc", &d, 1, 0.0);
    set_text_att(p, "rain", "units", "furlongs");
    unsigned errors = log_error_count();
    assert_null(cf_open(&p, 1, 256));
    assert_int_equal(log_error_count(), errors + 1);
    assert_non_null(strstr(log_last_error(), "variable rain"));
    assert_non_null(strstr(log_last_error(), "\"furlongs\""));

    p = write_hgrid("units2.cf.nc", &d, 1, 0.0);
    set_text_att(p, "ta", "units", "degF");
    assert_null(cf_open(&p, 1, 256));
    assert_non_null(strstr(log_last_error(), "variable ta"));
    p = write_hgrid("units3.cf.nc", &d, 1, 0.0);
    set_text_att(p, "z", "units", "hPa");
    assert_null(cf_open(&p, 1, 256));
    assert_non_null(strstr(log_last_error(), "not height levels"));

    /* Heights that go up and then down. */
    struct hgrid_write_desc cm = {.kind = HGRID_CM1};
    p = write_hgrid("mono.cm1.nc", &cm, 1, 0.0);
    int nc, id;
    assert_int_equal(nc_open(p, NC_WRITE, &nc), NC_NOERR);
    assert_int_equal(nc_inq_varid(nc, "zh", &id), NC_NOERR);
    size_t k = 5;
    float z = 0.1f; /* km: below level 4 */
    assert_int_equal(nc_put_var1_float(nc, id, &k, &z), NC_NOERR);
    assert_int_equal(nc_close(nc), NC_NOERR);
    errors = log_error_count();
    assert_null(cm1_open(&p, 1, 256));
    assert_int_equal(log_error_count(), errors + 1);
    assert_non_null(strstr(log_last_error(), "not monotone"));
    assert_non_null(strstr(log_last_error(), "zh"));

    /* Uneven columns. */
    p = write_hgrid("uneven.cm1.nc", &cm, 1, 0.0);
    assert_int_equal(nc_open(p, NC_WRITE, &nc), NC_NOERR);
    assert_int_equal(nc_inq_varid(nc, "xh", &id), NC_NOERR);
    z = 100.0f;
    k = NX - 1;
    assert_int_equal(nc_put_var1_float(nc, id, &k, &z), NC_NOERR);
    assert_int_equal(nc_close(nc), NC_NOERR);
    assert_null(cm1_open(&p, 1, 256));
    assert_non_null(strstr(log_last_error(), "not evenly spaced"));

    /* The budget. */
    p = write_hgrid("budget.cm1.nc", &cm, 1, 0.0);
    struct hgrid *h = cm1_open(&p, 1, 256);
    assert_non_null(h);
    struct hgrid_desc hd = {.memory_mb = 0.01};
    struct field_volume fv;
    assert_false(hgrid_read_step(h, 0, &hd, &fv, NULL));
    assert_non_null(strstr(log_last_error(), "data.memory"));
    assert_null(fv.q[0]);
    hgrid_close(h);

    /* A WRF file is neither. */
    const char *wrf = write_wrf("neither.wrf.nc", 1);
    assert_null(cm1_open(&wrf, 1, 256));
    assert_null(cf_open(&wrf, 1, 256));
}

static void test_probes(void **state)
{
    struct hgrid_write_desc cm = {.kind = HGRID_CM1}, cf = {.kind = HGRID_CF};
    const char *a = write_hgrid("probe.cm1.nc", &cm, 1, 0.0);
    const char *b = write_hgrid("probe.cf.nc", &cf, 1, 0.0);
    const char *w = write_wrf("probe.wrf.nc", 1);
    unsigned errors = log_error_count();
    assert_true(cm1_probe(a));
    assert_false(cf_probe(a));
    assert_true(cf_probe(b));
    assert_false(cm1_probe(b));
    assert_false(cm1_probe(w));
    assert_false(cf_probe(w));
    assert_false(cm1_probe(test_tmp_path("no-such-file.nc")));
    assert_false(cf_probe(test_write_file("text.nc", "netcdf x {}\n")));
    assert_int_equal(log_error_count(), errors); /* quiet */
}

/* x, y as longitude and latitude: spacings in metres on the sphere, and the georeference. */
static void test_cf_latlon(void **state)
{
    struct hgrid_write_desc d = {.kind = HGRID_CF, .latlon = true, .cen_lat = 30.0,
                                 .cen_lon = -80.0};
    const char *p = write_hgrid("ll.cf.nc", &d, 1, 0.0);
    struct data_source *s = open_source(DATA_SOURCE_CF, &p);
    assert_non_null(s);
    const struct hgrid_meta *m = hgrid_get_meta(data_source_hgrid(s));
    assert_true(m->latlon);
    /* The writer spaced the columns 1500 m apart at the centre latitude. */
    assert_float_equal(m->dy, 1500.0, 1e-3);
    assert_float_equal(m->dx, 1500.0, 1.0);
    struct geo_map g;
    assert_true(data_source_geo(s, &g));
    double lat, lon;
    assert_true(geo_map_to_latlon(&g, 0.5 * m->dx, 0.5 * m->dy, &lat, &lon));
    assert_float_equal(lat, m->lat0, 1e-4);
    assert_float_equal(lon, m->lon0, 1e-4);
    assert_float_equal(m->lat0 + 0.5 * (m->ny - 1) * m->dlat, 30.0, 1e-3);
    geo_map_finish(&g);

    /* Rows stored from the north (as many lat/lon files are): the same volume. */
    struct hgrid_write_desc dn = d;
    dn.north_first = true;
    const char *pn = write_hgrid("ll-north.cf.nc", &dn, 1, 0.0);
    struct data_source *sn = open_source(DATA_SOURCE_CF, &pn);
    assert_non_null(sn);
    const struct hgrid_meta *mn = hgrid_get_meta(data_source_hgrid(sn));
    assert_true(mn->flip[1] && !mn->flip[0]);
    assert_float_equal(mn->lat0, m->lat0, 1e-9);
    struct field_volume fa, fb;
    assert_true(data_source_load_fields(s, 0, &fa));
    assert_true(data_source_load_fields(sn, 0, &fb));
    size_t n = grid3_count(&fa.grid);
    for (int f = 0; f < SPECIES_COUNT; f++)
        assert_memory_equal(fa.q[f], fb.q[f], n * sizeof(float));
    field_volume_finish(&fa);
    field_volume_finish(&fb);
    data_source_close(sn);
    data_source_close(s);
}

static void test_units_table(void **state)
{
    double s, o;
    assert_true(hgrid_parse_units(HGRID_CLOUD, "g kg-1", &s, &o) && s == 1e-3 && o == 0.0);
    assert_true(hgrid_parse_units(HGRID_CLOUD, "kg kg**-1", &s, &o) && s == 1.0);
    assert_true(hgrid_parse_units(HGRID_CLOUD, "", &s, &o) && s == 1.0);
    assert_false(hgrid_parse_units(HGRID_CLOUD, "kg m-3", &s, &o));
    assert_true(hgrid_parse_units(HGRID_TEMPERATURE, "degC", &s, &o) && s == 1.0 && o == 273.15);
    assert_false(hgrid_parse_units(HGRID_TEMPERATURE, "degF", &s, &o));
    assert_true(hgrid_parse_units(HGRID_PRESSURE, "hPa", &s, &o) && s == 100.0);
    assert_true(hgrid_parse_units(HGRID_PRESSURE, "kPa", &s, &o) && s == 1000.0);
    assert_false(hgrid_parse_units(HGRID_PRESSURE, "K", &s, &o));
    assert_true(hgrid_parse_units(HGRID_U, "m s-1", &s, &o));
    assert_false(hgrid_parse_units(HGRID_U, "knots", &s, &o));
    assert_true(hgrid_parse_length("km", &s) && s == 1000.0);
    assert_true(hgrid_parse_length(" m ", &s) && s == 1.0);
    assert_false(hgrid_parse_length("ft", &s));
}

int main(void)
{
    log_set_level(LOG_ERROR);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_same_storm),   cmocka_unit_test(test_cm1_temperature_wind),
        cmocka_unit_test(test_times),        cmocka_unit_test(test_cf_variants),
        cmocka_unit_test(test_missing_species), cmocka_unit_test(test_errors),
        cmocka_unit_test(test_probes),       cmocka_unit_test(test_cf_latlon),
        cmocka_unit_test(test_units_table),  cmocka_unit_test(test_cf_wind_components),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
