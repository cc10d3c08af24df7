/* WRF nests (data/nest.h): a parent and a nest written here from one analytic field, placed by
 * their PARENT attributes and by their latitude and longitude (the same place), composed at
 * the nest's spacing (the nest's columns kept, the parent's read as trilinear sampling reads
 * them), matched by Times, counted against the memory budget, and the errors: a nest outside
 * its parent, a ratio its spacing contradicts. */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "data/nest.h"
#include "data/source.h"
#include "data/wrf.h"
#include "data/wrf_write.h"

#define PI 3.14159265358979323846
#define DX 3000.0 /* parent spacing, m */
#define NXP 16    /* parent columns */
#define NZ 8
#define DZ 500.0
#define RATIO 3
#define IPS 6 /* nest's first parent column, 1-based */
#define JPS 5
#define NNEST 6 /* parent columns the nest covers */

/* The field both domains sample at their own voxel centres (x, y from the parent's west and
 * south edge): cloud in a slab, varying across the columns. */
static double field(double x, double y, double z)
{
    if (z < 1000.0 || z > 3000.0)
        return 0.0;
    return 1e-3 * (1.0 + 0.5 * sin(2.0 * PI * x / 30000.0) * cos(2.0 * PI * y / 36000.0));
}

/* GRID sampled at its voxel centres; X0, Y0: its west and south edge in the parent's frame. */
static void fill(const struct grid3 *g, double x0, double y0, struct field_volume *fv)
{
    memset(fv, 0, sizeof(*fv));
    fv->grid = *g;
    fv->q[SPECIES_CLOUD] = calloc(grid3_count(g), sizeof(float));
    assert_non_null(fv->q[SPECIES_CLOUD]);
    for (int k = 0; k < g->n[2]; k++)
        for (int j = 0; j < g->n[1]; j++)
            for (int i = 0; i < g->n[0]; i++)
                fv->q[SPECIES_CLOUD][grid3_index(g, i, j, k)] =
                    (float)field(x0 + (i + 0.5) * g->spacing[0], y0 + (j + 0.5) * g->spacing[1],
                                 (k + 0.5) * g->spacing[2]);
}

struct pair {
    int ips, jps, ratio_att, nnest;
    bool latlon_only;
    int nest_steps; /* of the two dates */
};

static const char *dates[2] = {"2005-08-28_12:00:00", "2005-08-28_13:00:00"};

/* Writes NAME_d01.nc and NAME_d02.nc; P NULL: the default pair. */
static void write_pair(const char *name, const struct pair *p_in)
{
    struct pair p = {IPS, JPS, RATIO, NNEST, false, 2};
    if (p_in)
        p = *p_in;
    char path[512];
    struct grid3 pg = {.n = {NXP, NXP, NZ}, .spacing = {DX, DX, DZ}, .origin = {0, 0, 0}};
    struct grid3 ng = {.n = {p.nnest * RATIO, p.nnest * RATIO, NZ},
                       .spacing = {DX / RATIO, DX / RATIO, DZ},
                       .origin = {0, 0, 0}};
    double ex = NXP * DX;
    struct wrf_write_desc pd = {.cen_lat = 25.0,
                                .cen_lon = -89.0,
                                .grid_id = 1,
                                .parent_id = 1,
                                .i_parent_start = 1,
                                .j_parent_start = 1,
                                .parent_grid_ratio = 1,
                                .map_corner_m = {-0.5 * ex, -0.5 * ex}};
    struct wrf_write_desc nd = pd;
    nd.grid_id = 2;
    nd.i_parent_start = p.ips;
    nd.j_parent_start = p.jps;
    nd.parent_grid_ratio = p.ratio_att;
    nd.latlon_only = p.latlon_only;
    nd.map_corner_m[0] += (p.ips - 1) * DX;
    nd.map_corner_m[1] += (p.jps - 1) * DX;
    struct field_volume fv;
    snprintf(path, sizeof(path), "%s", test_tmp_path(name));
    strcat(path, "_d01.nc");
    struct wrf_writer *w = wrf_writer_create(path, &pg, &pd);
    assert_non_null(w);
    fill(&pg, 0.0, 0.0, &fv);
    for (int s = 0; s < 2; s++)
        assert_true(wrf_writer_add(w, &fv, dates[s]));
    field_volume_finish(&fv);
    assert_true(wrf_writer_finish(w));
    snprintf(path, sizeof(path), "%s", test_tmp_path(name));
    strcat(path, "_d02.nc");
    w = wrf_writer_create(path, &ng, &nd);
    assert_non_null(w);
    fill(&ng, (p.ips - 1) * DX, (p.jps - 1) * DX, &fv);
    for (int s = 0; s < p.nest_steps; s++)
        assert_true(wrf_writer_add(w, &fv, dates[s]));
    field_volume_finish(&fv);
    assert_true(wrf_writer_finish(w));
}

static struct nest_set *open_pair(const char *name, bool *single)
{
    char a[512], b[512];
    snprintf(a, sizeof(a), "%s_d01.nc", test_tmp_path(name));
    snprintf(b, sizeof(b), "%s_d02.nc", test_tmp_path(name));
    const char *paths[2] = {b, a}; /* any order */
    return nest_open(paths, 2, 0.0, single);
}

/* A hand-made layout: outside the nest the composite reads the parent as bilinear sampling
 * does (its own columns exactly, the ratio being odd), inside it the nest's columns exactly,
 * and across one parent column at the nest's edge a blend between the two. */
static void test_compose_layout(void **state)
{
    (void)state;
    struct nest_layout l = {.count = 2};
    l.grid = (struct grid3){.n = {12, 12, 2}, .spacing = {1.0, 1.0, 1.0}, .origin = {0, 0, 0}};
    l.place[0] = (struct nest_place){{0, 0}, 3, 0};
    l.place[1] = (struct nest_place){{3, 3}, 1, 3};
    struct field_volume in[2];
    memset(in, 0, sizeof(in));
    in[0].grid = (struct grid3){.n = {4, 4, 2}, .spacing = {3.0, 3.0, 1.0}, .origin = {0, 0, 0}};
    in[1].grid = (struct grid3){.n = {9, 9, 2}, .spacing = {1.0, 1.0, 1.0}, .origin = {3, 3, 0}};
    in[0].q[SPECIES_RAIN] = calloc(32, sizeof(float));
    in[1].q[SPECIES_RAIN] = calloc(162, sizeof(float));
    for (int i = 0; i < 32; i++)
        in[0].q[SPECIES_RAIN][i] = (float)(1 + i % 4 + 10 * (i / 4));
    for (int i = 0; i < 162; i++)
        in[1].q[SPECIES_RAIN][i] = 1000.0f + (float)i;
    struct field_volume out;
    assert_true(nest_compose(&l, in, &out));
    assert_non_null(out.q[SPECIES_RAIN]);
    assert_null(out.q[SPECIES_CLOUD]);
    assert_null(out.rho_air); /* not in the domains: the standard atmosphere */
    const float *c = out.q[SPECIES_RAIN];
    /* The parent's columns where no nest is. */
    for (int k = 0; k < 2; k++)
        for (int j = 0; j < 4; j++)
            for (int i = 0; i < 4; i++) {
                if (i >= 1 && i <= 3 && j >= 1 && j <= 3)
                    continue;
                assert_true(c[grid3_index(&l.grid, 3 * i + 1, 3 * j + 1, k)] ==
                            in[0].q[SPECIES_RAIN][grid3_index(&in[0].grid, i, j, k)]);
            }
    /* Between them, the parent linear: column 3 * 0 + 2 is a third of the way to column 1. */
    float a = in[0].q[SPECIES_RAIN][0], b = in[0].q[SPECIES_RAIN][1];
    assert_float_equal(c[grid3_index(&l.grid, 2, 0, 0)], a + (b - a) / 3.0, 1e-5);
    /* The edge columns clamp, as the sampler does. */
    assert_true(c[0] == a);
    /* The nest's middle parent column (e >= 3 composite columns from its edge): its own. */
    for (int j = 6; j < 9; j++)
        for (int i = 6; i < 9; i++)
            assert_true(c[grid3_index(&l.grid, i, j, 1)] ==
                        in[1].q[SPECIES_RAIN][grid3_index(&in[1].grid, i - 3, j - 3, 1)]);
    /* Its outermost column (composite column 3, centre 3.5 = parent column 0.67; row 7 on
     * parent row 2): a sixth of the nest, the rest the parent there. */
    const float *p = in[0].q[SPECIES_RAIN];
    double under =
        p[grid3_index(&in[0].grid, 0, 2, 0)] +
        (p[grid3_index(&in[0].grid, 1, 2, 0)] - p[grid3_index(&in[0].grid, 0, 2, 0)]) * 2.0 / 3.0;
    double nest = in[1].q[SPECIES_RAIN][grid3_index(&in[1].grid, 0, 4, 0)];
    assert_float_equal(c[grid3_index(&l.grid, 3, 7, 0)], under + (nest - under) / 6.0, 1e-3);
    field_volume_finish(&out);

    /* A nest the grid cuts writes only what the grid holds (a crop); its columns there are
     * its own. */
    l.place[1].offset[0] = 6;
    assert_true(nest_compose(&l, in, &out));
    assert_true(out.q[SPECIES_RAIN][grid3_index(&l.grid, 11, 7, 1)] ==
                in[1].q[SPECIES_RAIN][grid3_index(&in[1].grid, 5, 4, 1)]);
    field_volume_finish(&out);
    /* Other heights are refused. */
    in[1].grid.n[2] = 1;
    log_set_level(LOG_NONE);
    assert_false(nest_compose(&l, in, &out));
    log_set_level(LOG_WARN);
    assert_non_null(strstr(log_last_error(), "does not fit the composite"));
    field_volume_finish(&in[0]);
    field_volume_finish(&in[1]);
}

/* The written pair: placed by its attributes, composed on 48 x 48 columns of 1 km, the nest's
 * values where it is and the parent's elsewhere. */
static void test_pair_placed_and_composed(void **state)
{
    (void)state;
    write_pair("att", NULL);
    bool single = false;
    struct nest_set *s = open_pair("att", &single);
    assert_non_null(s);
    assert_false(single);
    assert_int_equal(nest_domain_count(s), 2);
    const struct nest_domain *d1 = nest_domain(s, 1);
    assert_int_equal(nest_domain(s, 0)->grid_id, 1);
    assert_int_equal(d1->grid_id, 2);
    assert_false(d1->by_latlon);
    assert_int_equal(d1->start[0], IPS);
    assert_int_equal(d1->start[1], JPS);
    assert_int_equal(d1->ratio, RATIO);
    /* Its XLAT/XLONG put it where the attributes do. */
    assert_true(d1->misfit_m < 0.05 * DX / RATIO);
    char line[512];
    nest_describe(s, 1, line, sizeof(line));
    assert_non_null(strstr(line, "XLAT/XLONG agree within"));
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    struct nest_layout l;
    assert_true(nest_layout(s, &d, &l));
    assert_int_equal(l.grid.n[0], NXP * RATIO);
    assert_int_equal(l.grid.n[2], NZ);
    assert_float_equal(l.grid.spacing[0], DX / RATIO, 1e-3);
    assert_int_equal(l.place[1].offset[0], (IPS - 1) * RATIO);
    assert_int_equal(l.place[1].offset[1], (JPS - 1) * RATIO);

    struct field_volume fv;
    assert_true(nest_read_step(s, 1, &d, &fv, NULL));
    assert_int_equal(fv.grid.n[0], NXP * RATIO);
    const float *q = fv.q[SPECIES_CLOUD];
    double worst_in = 0.0, worst_out = 0.0;
    for (int j = 0; j < fv.grid.n[1]; j++)
        for (int i = 0; i < fv.grid.n[0]; i++) {
            int k = 3;
            double x = (i + 0.5) * fv.grid.spacing[0], y = (j + 0.5) * fv.grid.spacing[1];
            double truth = field(x, y, (k + 0.5) * DZ);
            double got = q[grid3_index(&fv.grid, i, j, k)];
            bool inner = i >= l.place[1].offset[0] + RATIO &&
                         i < l.place[1].offset[0] + (NNEST - 1) * RATIO &&
                         j >= l.place[1].offset[1] + RATIO &&
                         j < l.place[1].offset[1] + (NNEST - 1) * RATIO;
            if (inner)
                worst_in = fmax(worst_in, fabs(got - truth));
            else if (i % RATIO == 1 && j % RATIO == 1)
                worst_out = fmax(worst_out, fabs(got - truth));
        }
    /* The nest's own columns exactly (float rounding); the parent's at its column centres. */
    assert_true(worst_in < 1e-9);
    assert_true(worst_out < 1e-9);
    field_volume_finish(&fv);

    /* The budget counts both domains and the composite. */
    size_t all = nest_step_bytes(s, &d);
    size_t outer = wrf_step_bytes(nest_outer(s), &d);
    assert_true(all > outer * (1 + RATIO * RATIO));
    d.memory_mb = (double)outer * 2.0 / 1048576.0;
    log_set_level(LOG_NONE);
    assert_false(nest_read_step(s, 0, &d, &fv, NULL));
    log_set_level(LOG_WARN);
    assert_non_null(strstr(log_last_error(), "data.memory"));
    nest_close(s);
}

/* The same nest without its PARENT attributes lands on the same columns from its XLAT/XLONG. */
static void test_latlon_agrees(void **state)
{
    (void)state;
    struct pair p = {IPS, JPS, RATIO, NNEST, true, 2};
    write_pair("ll", &p);
    bool single;
    struct nest_set *s = open_pair("ll", &single);
    assert_non_null(s);
    const struct nest_domain *d1 = nest_domain(s, 1);
    assert_true(d1->by_latlon);
    assert_int_equal(d1->start[0], IPS);
    assert_int_equal(d1->start[1], JPS);
    assert_int_equal(d1->ratio, RATIO);
    assert_true(d1->misfit_m < 0.05 * DX / RATIO);
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    struct nest_layout l;
    assert_true(nest_layout(s, &d, &l));
    assert_int_equal(l.place[1].offset[0], (IPS - 1) * RATIO);
    assert_int_equal(l.place[1].offset[1], (JPS - 1) * RATIO);
    char line[512];
    nest_describe(s, 1, line, sizeof(line));
    assert_non_null(strstr(line, "XLAT/XLONG"));
    nest_close(s);
}

/* Attributes that put a nest a parent column away from where its latitude and longitude do
 * (files of two runs): a warning, the attributes kept. */
static void test_attributes_against_latlon(void **state)
{
    (void)state;
    write_pair("two", NULL);
    /* The nest's lat/lon as written for IPS; its attributes say IPS + 2. */
    struct grid3 ng = {.n = {NNEST * RATIO, NNEST * RATIO, NZ},
                       .spacing = {DX / RATIO, DX / RATIO, DZ},
                       .origin = {0, 0, 0}};
    double ex = NXP * DX;
    struct wrf_write_desc nd = {
        .cen_lat = 25.0,
        .cen_lon = -89.0,
        .grid_id = 2,
        .parent_id = 1,
        .i_parent_start = IPS + 2,
        .j_parent_start = JPS,
        .parent_grid_ratio = RATIO,
        .map_corner_m = {-0.5 * ex + (IPS - 1) * DX, -0.5 * ex + (JPS - 1) * DX}};
    char path[512];
    snprintf(path, sizeof(path), "%s_d02.nc", test_tmp_path("two"));
    struct wrf_writer *w = wrf_writer_create(path, &ng, &nd);
    assert_non_null(w);
    struct field_volume fv;
    fill(&ng, (IPS - 1) * DX, (JPS - 1) * DX, &fv);
    assert_true(wrf_writer_add(w, &fv, dates[0]));
    field_volume_finish(&fv);
    assert_true(wrf_writer_finish(w));
    unsigned warns = log_warn_count();
    log_set_level(LOG_NONE);
    bool single;
    struct nest_set *s = open_pair("two", &single);
    log_set_level(LOG_WARN);
    assert_non_null(s);
    assert_int_equal(log_warn_count(), warns + 1);
    assert_non_null(strstr(log_last_warning(), "a nest of another run?"));
    assert_int_equal(nest_domain(s, 1)->start[0], IPS + 2);
    assert_float_equal(nest_domain(s, 1)->misfit_m, 2 * DX, 1.0);
    nest_close(s);
}

/* Times: a nest without the parent's second step leaves that step to the parent. */
static void test_times_matched(void **state)
{
    (void)state;
    struct pair p = {IPS, JPS, RATIO, NNEST, false, 1};
    write_pair("one", &p);
    bool single;
    struct nest_set *s = open_pair("one", &single);
    assert_non_null(s);
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    struct field_volume a, b;
    assert_true(nest_read_step(s, 0, &d, &a, NULL));
    unsigned warns = log_warn_count();
    log_set_level(LOG_NONE);
    assert_true(nest_read_step(s, 1, &d, &b, NULL));
    log_set_level(LOG_WARN);
    assert_int_equal(log_warn_count(), warns + 1);
    assert_non_null(strstr(log_last_warning(), "no step at 2005-08-28_13:00:00"));
    /* Inside the nest, step 0 has the nest's values, step 1 the parent's interpolation. */
    size_t at = grid3_index(&a.grid, (IPS + 2) * RATIO, (JPS + 2) * RATIO, 3);
    double x = ((IPS + 2) * RATIO + 0.5) * a.grid.spacing[0];
    double y = ((JPS + 2) * RATIO + 0.5) * a.grid.spacing[1];
    assert_float_equal(a.q[SPECIES_CLOUD][at], field(x, y, 3.5 * DZ), 1e-9);
    assert_true(fabs(b.q[SPECIES_CLOUD][at] - a.q[SPECIES_CLOUD][at]) > 1e-7);
    field_volume_finish(&a);
    field_volume_finish(&b);
    nest_close(s);
}

/* One domain is no nest set: opened as before. */
static void test_single_domain(void **state)
{
    (void)state;
    write_pair("solo", NULL);
    char a[512];
    snprintf(a, sizeof(a), "%s_d01.nc", test_tmp_path("solo"));
    const char *paths[1] = {a};
    bool single = false;
    assert_null(nest_open(paths, 1, 0.0, &single));
    assert_true(single);
    /* A pattern over both domains groups them. */
    snprintf(a, sizeof(a), "%s_d0*.nc", test_tmp_path("solo"));
    struct nest_set *s = nest_open(paths, 1, 0.0, &single);
    assert_non_null(s);
    assert_int_equal(nest_domain_count(s), 2);
    nest_close(s);
}

/* Three levels: d03 inside d02 inside d01, each placed in its parent, composed at d03's
 * spacing; d03's columns exact, given in any order. */
static void test_three_levels(void **state)
{
    (void)state;
    struct grid3 g1 = {.n = {NXP, NXP, NZ}, .spacing = {DX, DX, DZ}, .origin = {0, 0, 0}};
    struct grid3 g2 = {.n = {18, 18, NZ}, .spacing = {DX / 3, DX / 3, DZ}, .origin = {0, 0, 0}};
    struct grid3 g3 = {.n = {9, 12, NZ}, .spacing = {DX / 9, DX / 9, DZ}, .origin = {0, 0, 0}};
    double ex = NXP * DX;
    struct wrf_write_desc d1 = {.cen_lat = 25.0,
                                .cen_lon = -89.0,
                                .grid_id = 1,
                                .parent_id = 1,
                                .i_parent_start = 1,
                                .j_parent_start = 1,
                                .parent_grid_ratio = 1,
                                .map_corner_m = {-0.5 * ex, -0.5 * ex}};
    struct wrf_write_desc d2 = d1, d3 = d1;
    d2.grid_id = 2;
    d2.i_parent_start = 6;
    d2.j_parent_start = 5;
    d2.parent_grid_ratio = 3;
    d3.grid_id = 3;
    d3.parent_id = 2;
    d3.i_parent_start = 7;
    d3.j_parent_start = 4;
    d3.parent_grid_ratio = 3;
    double x2 = 5 * DX, y2 = 4 * DX, x3 = x2 + 6 * DX / 3, y3 = y2 + 3 * DX / 3;
    const struct {
        const char *name;
        const struct grid3 *g;
        struct wrf_write_desc *d;
        double x0, y0;
    } dom[3] = {{"three_d01.nc", &g1, &d1, 0, 0},
                {"three_d02.nc", &g2, &d2, x2, y2},
                {"three_d03.nc", &g3, &d3, x3, y3}};
    char paths[3][512];
    for (int i = 0; i < 3; i++) {
        snprintf(paths[i], sizeof(paths[i]), "%s", test_tmp_path(dom[i].name));
        dom[i].d->map_corner_m[0] += dom[i].x0;
        dom[i].d->map_corner_m[1] += dom[i].y0;
        struct wrf_writer *w = wrf_writer_create(paths[i], dom[i].g, dom[i].d);
        assert_non_null(w);
        struct field_volume fv;
        fill(dom[i].g, dom[i].x0, dom[i].y0, &fv);
        assert_true(wrf_writer_add(w, &fv, dates[0]));
        field_volume_finish(&fv);
        assert_true(wrf_writer_finish(w));
    }
    const char *order[3] = {paths[2], paths[0], paths[1]};
    bool single;
    struct nest_set *s = nest_open(order, 3, 0.0, &single);
    assert_non_null(s);
    assert_int_equal(nest_domain_count(s), 3);
    assert_int_equal(nest_domain(s, 2)->grid_id, 3);
    assert_int_equal(nest_domain(s, 2)->parent_id, 2);
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    struct nest_layout l;
    assert_true(nest_layout(s, &d, &l));
    assert_int_equal(l.grid.n[0], NXP * 9);
    assert_int_equal(l.place[1].offset[0], 5 * 9);
    assert_int_equal(l.place[2].offset[0], 5 * 9 + 6 * 3);
    assert_int_equal(l.place[2].offset[1], 4 * 9 + 3 * 3);
    assert_int_equal(l.place[2].blend, 3); /* one d02 column */
    struct field_volume fv;
    assert_true(nest_read_step(s, 0, &d, &fv, NULL));
    /* d03's middle column, and d02's where d03 is not (beyond its blend with d01). */
    int i3 = l.place[2].offset[0] + 4, j3 = l.place[2].offset[1] + 6, k = 3;
    double truth =
        field((i3 + 0.5) * fv.grid.spacing[0], (j3 + 0.5) * fv.grid.spacing[1], (k + 0.5) * DZ);
    assert_float_equal(fv.q[SPECIES_CLOUD][grid3_index(&fv.grid, i3, j3, k)], truth, 1e-9);
    int i2 = l.place[1].offset[0] + 3 * 4 + 1, j2 = l.place[1].offset[1] + 3 * 14 + 1;
    truth = field((i2 + 0.5) * fv.grid.spacing[0], (j2 + 0.5) * fv.grid.spacing[1], (k + 0.5) * DZ);
    assert_float_equal(fv.q[SPECIES_CLOUD][grid3_index(&fv.grid, i2, j2, k)], truth, 1e-9);
    field_volume_finish(&fv);
    nest_close(s);
}

static void expect_refused(const char *name, const struct pair *p, const char *words)
{
    write_pair(name, p);
    bool single = true;
    log_set_level(LOG_NONE);
    struct nest_set *s = open_pair(name, &single);
    log_set_level(LOG_WARN);
    assert_null(s);
    assert_false(single);
    const char *e = log_last_error();
    assert_non_null(strstr(e, words));
    /* The message names the nest's file. */
    char file[512];
    snprintf(file, sizeof(file), "%s_d02.nc", test_tmp_path(name));
    assert_non_null(strstr(e, file));
}

static void test_errors(void **state)
{
    (void)state;
    /* Beyond the parent's east edge by one column; then by lat/lon. */
    struct pair out = {NXP - NNEST + 2, JPS, RATIO, NNEST, false, 2};
    expect_refused("out", &out, "does not fit inside it");
    out.latlon_only = true;
    expect_refused("outll", &out, "does not fit inside it");
    /* A start far beyond the parent (no overflow on the way to the message). */
    struct pair huge = {1 << 30, JPS, RATIO, NNEST, false, 2};
    expect_refused("huge", &huge, "starts at column 1073741824, 5 of");
    /* PARENT_GRID_RATIO 2 on a grid 3 times finer. */
    struct pair ratio = {IPS, JPS, 2, NNEST, false, 2};
    expect_refused("ratio", &ratio, "PARENT_GRID_RATIO 2");

    /* The source refuses a stride with nests, and a crop beyond the composite, naming the
     * file. */
    write_pair("crop", NULL);
    char a[512], b[512];
    snprintf(a, sizeof(a), "%s_d01.nc", test_tmp_path("crop"));
    snprintf(b, sizeof(b), "%s_d02.nc", test_tmp_path("crop"));
    const char *files[2] = {a, b};
    struct data_source_desc sd = {.format = DATA_SOURCE_WRF, .files = files, .file_count = 2};
    wrf_desc_defaults(&sd.wrf);
    optics_params_defaults(&sd.optics);
    species_select_defaults(&sd.select);
    sd.wrf.stride[0] = 2;
    log_set_level(LOG_NONE);
    assert_null(data_source_open(&sd));
    log_set_level(LOG_WARN);
    assert_non_null(strstr(log_last_error(), "data.stride"));
    assert_non_null(strstr(log_last_error(), a));
    sd.wrf.stride[0] = 0;
    sd.wrf.crop[1] = NXP * RATIO; /* one past the last composite column */
    log_set_level(LOG_NONE);
    assert_null(data_source_open(&sd));
    log_set_level(LOG_WARN);
    assert_non_null(strstr(log_last_error(), "data.crop along x keeps columns 0 to 48"));
    /* Without them, the source's grid is the composite's and a step loads on it. */
    sd.wrf.crop[1] = -1;
    struct data_source *src = data_source_open(&sd);
    assert_non_null(src);
    struct grid3 g;
    assert_true(data_source_grid(src, &g));
    assert_int_equal(g.n[0], NXP * RATIO);
    struct ext_volume v;
    assert_true(data_source_load(src, 0, &v, NULL, NULL));
    assert_int_equal(v.grid.n[1], NXP * RATIO);
    ext_volume_finish(&v);
    data_source_close(src);
}

/* data.crop with nests counts the composite's columns (and levels along z): the cropped step is
 * that part of the whole composite, value for value; a nest outside the crop is not read. */
static void test_crop(void **state)
{
    (void)state;
    write_pair("cut", NULL);
    bool single;
    struct nest_set *s = open_pair("cut", &single);
    assert_non_null(s);
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    struct field_volume whole, part;
    assert_true(nest_read_step(s, 0, &d, &whole, NULL));
    /* Across the nest's west edge, rows through it, levels 2 to 5. */
    int c[6] = {10, 25, 12, 40, 2, 5};
    memcpy(d.crop, c, sizeof(c));
    struct nest_layout l;
    assert_true(nest_layout(s, &d, &l));
    assert_int_equal(l.grid.n[0], 16);
    assert_int_equal(l.grid.n[1], 29);
    assert_int_equal(l.grid.n[2], 4);
    assert_float_equal(l.grid.origin[0], 10 * DX / RATIO, 1e-6);
    assert_float_equal(l.grid.origin[2], 2 * DZ, 1e-6);
    assert_true(nest_read_step(s, 0, &d, &part, NULL));
    assert_int_equal(part.grid.n[0], 16);
    for (int k = 0; k < 4; k++)
        for (int j = 0; j < 29; j++)
            for (int i = 0; i < 16; i++)
                assert_true(
                    part.q[SPECIES_CLOUD][grid3_index(&part.grid, i, j, k)] ==
                    whole.q[SPECIES_CLOUD][grid3_index(&whole.grid, i + 10, j + 12, k + 2)]);
    field_volume_finish(&part);
    size_t with = nest_step_bytes(s, &d);
    /* West of the nest: the nest is not read, and not counted. */
    int w[6] = {0, 9, 0, 47, -1, -1};
    memcpy(d.crop, w, sizeof(w));
    assert_true(nest_step_bytes(s, &d) < with);
    assert_true(nest_read_step(s, 0, &d, &part, NULL));
    for (int j = 0; j < 48; j++)
        for (int i = 0; i < 10; i++)
            assert_true(part.q[SPECIES_CLOUD][grid3_index(&part.grid, i, j, 3)] ==
                        whole.q[SPECIES_CLOUD][grid3_index(&whole.grid, i, j, 3)]);
    field_volume_finish(&part);
    field_volume_finish(&whole);
    nest_close(s);
}

/* The probe's point: the nest's columns where it is, the parent's elsewhere, nothing outside
 * a crop. */
static void test_point(void **state)
{
    (void)state;
    write_pair("pt", NULL);
    bool single;
    struct nest_set *s = open_pair("pt", &single);
    assert_non_null(s);
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    struct wrf_point wp;
    /* A nest column's centre (its column 4, 7) and a parent column's away from it. */
    double inside[3] = {(IPS - 1) * DX + 4.5 * DX / RATIO, (JPS - 1) * DX + 7.5 * DX / RATIO,
                        3.5 * DZ};
    assert_int_equal(nest_read_point(s, 0, &d, inside, &wp), WRF_POINT_OK);
    assert_float_equal(wp.q[SPECIES_CLOUD], field(inside[0], inside[1], inside[2]), 1e-9);
    double away[3] = {1.5 * DX, 13.5 * DX, 3.5 * DZ};
    assert_int_equal(nest_read_point(s, 0, &d, away, &wp), WRF_POINT_OK);
    assert_float_equal(wp.q[SPECIES_CLOUD], field(away[0], away[1], away[2]), 1e-9);
    /* Between nest columns the parent's interpolation would differ from the field by more than
     * the nest's does. */
    double mid[3] = {inside[0] + 0.5 * DX / RATIO, inside[1], inside[2]};
    assert_int_equal(nest_read_point(s, 0, &d, mid, &wp), WRF_POINT_OK);
    double truth = field(mid[0], mid[1], mid[2]);
    double nest_err = fabs(wp.q[SPECIES_CLOUD] - truth);
    struct wrf_point pp;
    struct wrf_desc od;
    wrf_desc_defaults(&od);
    od.levels = NZ;
    assert_int_equal(wrf_read_point(nest_outer(s), 0, &od, mid, &pp), WRF_POINT_OK);
    assert_true(nest_err < 0.5 * fabs(pp.q[SPECIES_CLOUD] - truth));
    int c[6] = {0, 9, -1, -1, -1, -1};
    memcpy(d.crop, c, sizeof(c));
    assert_int_equal(nest_read_point(s, 0, &d, inside, &wp), WRF_POINT_OUTSIDE);
    nest_close(s);
}

int main(void)
{
    log_set_level(LOG_WARN);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_compose_layout), cmocka_unit_test(test_pair_placed_and_composed),
        cmocka_unit_test(test_latlon_agrees),  cmocka_unit_test(test_attributes_against_latlon),
        cmocka_unit_test(test_times_matched),  cmocka_unit_test(test_single_domain),
        cmocka_unit_test(test_crop),           cmocka_unit_test(test_point),
        cmocka_unit_test(test_three_levels),   cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
