/* The model's own vertical levels (data.vertical = native): the stretched grid's height
 * mapping, a synthetic WRF file's thin layer read where the model put it, and the CPU
 * reference's transmittance through it; the uniform 439 m grid misses it.  The same layer in
 * CM1 and CF files kept on the file's own heights, values copied. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"
#include "thin_layer.h"

#include "common/log.h"
#include "data/cf.h"
#include "data/cm1.h"
#include "data/extfile.h"
#include "data/hgrid.h"
#include "data/hgrid_write.h"
#include "data/nest.h"
#include "data/source.h"
#include "data/volume.h"
#include "data/wrf.h"
#include "reference/reference.h"

/* Reads the thin-layer file natively (or on 14 uniform levels) into an extinction volume. */
static void read_layer(bool native, struct field_volume *fv, struct ext_volume *ev)
{
    const char *path = test_tmp_path("thin.nc");
    assert_true(thin_layer_write(path));
    const char *files[] = {path};
    struct wrf *w = wrf_open(files, 1, 1024.0);
    assert_non_null(w);
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    d.native_levels = native;
    d.levels = native ? 0 : 14;
    struct grid3 g;
    assert_true(wrf_grid(w, &d, &g));
    log_set_level(LOG_ERROR);
    assert_true(wrf_read_step(w, 0, &d, fv, NULL));
    log_set_level(LOG_INFO);
    /* wrf_grid repeats wrf_read_step's output grid. */
    assert_true(grid3_equal(&g, &fv->grid));
    wrf_close(w);
    struct optics_params optics;
    optics_params_defaults(&optics);
    struct species_select sel;
    species_select_defaults(&sel);
    assert_true(ext_volume_from_fields(fv, &optics, &sel, ev));
}

/* The layer's optical depth from the file: its extinction over the 100 m between its faces
 * (linear in height between the level centres, the hat of level 2 holds exactly that). */
static double layer_tau(const struct ext_volume *ev)
{
    size_t plane = (size_t)ev->grid.n[0] * ev->grid.n[1];
    size_t v = plane * THIN_LAYER_LEVEL + 2 + 6 * 3;
    return (ev->beta[2 * v] + ev->beta[2 * v + 1]) * (THIN_LAYER_TOP_M - THIN_LAYER_BOTTOM_M);
}

static void test_mapping(void **state)
{
    (void)state;
    struct grid3 g = {.n = {1, 1, 0}, .spacing = {1, 1, 0}};
    const double zc[3] = {10.0, 30.0, 100.0};
    log_set_level(LOG_NONE);
    assert_false(grid3_set_levels(&g, (const double[]){10.0, 5.0}, 2, 0.0, 100.0));
    log_set_level(LOG_INFO);
    assert_true(grid3_set_levels(&g, zc, 3, 0.0, 200.0));
    assert_true(g.n[2] == 3 && fabs(g.spacing[2] - 200.0 / 3.0) < 1e-12);
    for (int k = 0; k < 3; k++) {
        assert_true(fabs(grid3_z_to_voxel(&g, zc[k]) - (k + 0.5)) < 1e-12);
        assert_true(fabs(grid3_voxel_to_z(&g, k + 0.5) - zc[k]) < 1e-12);
    }
    assert_true(grid3_z_to_voxel(&g, 0.0) == 0.0 && grid3_z_to_voxel(&g, 200.0) == 3.0);
    assert_true(fabs(grid3_z_to_voxel(&g, 20.0) - 1.0) < 1e-12); /* half way 10 .. 30 */
    assert_true(fabs(grid3_level_dz(&g, 1) - 45.0) < 1e-12);      /* 20 .. 65 */
    assert_true(fabs(grid3_min_dz(&g) - 20.0) < 1e-12);
    int k0, k1;
    grid3_z_voxel_range(&g, 12.0, 14.0, &k0, &k1);
    assert_true(k0 == 0 && k1 == 1);
    /* The GPU's table agrees with the mapping to a small part of the thinnest level. */
    int n = grid3_zmap_entries(&g);
    float *t = malloc((size_t)n * sizeof(float));
    grid3_zmap_fill(&g, n, t, NULL);
    for (int i = 0; i < 1000; i++) {
        double z = 200.0 * i / 999.0, f = z / 200.0 * (n - 1);
        int e = (int)f < n - 2 ? (int)f : n - 2;
        double u = (t[e] + (f - e) * (t[e + 1] - t[e])) * 3.0;
        assert_true(fabs(u - grid3_z_to_voxel(&g, z)) < 0.05);
    }
    free(t);
    /* Height exaggeration stretches the levels too. */
    struct ext_volume ev;
    assert_true(ext_volume_init(&ev, &g));
    ext_volume_stretch_height(&ev, 2.0);
    assert_true(ev.grid.z_centre[2] == 200.0 && ev.grid.spacing[2] == g.spacing[2] * 2.0);
    ext_volume_finish(&ev);
}

/* The CPU reference's optical depth up the column at (2.5, 3.5) km through EV's lowest
 * 2 km. */
static double column_tau(const struct ext_volume *ev)
{
    struct reference_desc rd;
    reference_desc_defaults(&rd);
    struct reference *ref = reference_create(ev, &rd);
    assert_non_null(ref);
    double sum = 0.0, dz = 0.01;
    for (double z = 0.5 * dz; z < 2000.0; z += dz) {
        double b[2];
        reference_beta(ref, (const double[3]){2500.0, 3500.0, z}, b);
        sum += (b[0] + b[1]) * dz;
    }
    reference_destroy(ref);
    return sum;
}

/* The CPU reference on EV: its extinction integrates to TAU up a column at the layer's
 * height, and its transmittance (residual ratio tracking, unbiased) straight down is e^-TAU. */
static void reference_keeps_the_layer(const struct ext_volume *ev, double tau, const char *what)
{
    struct reference_desc rd;
    reference_desc_defaults(&rd);
    struct reference *ref = reference_create(ev, &rd);
    assert_non_null(ref);
    double sum = 0.0, dz = 0.01, cloud_lo = 1e9, cloud_hi = -1e9;
    for (double z = 0.5 * dz; z < 1000.0; z += dz) {
        double b[2];
        reference_beta(ref, (const double[3]){2500.0, 3500.0, z}, b);
        sum += (b[0] + b[1]) * dz;
        if (b[0] + b[1] > 0.0) {
            cloud_lo = fmin(cloud_lo, z);
            cloud_hi = fmax(cloud_hi, z);
        }
    }
    assert_true(fabs(sum - tau) < 1e-3 * tau);
    /* At its height: from the centre below it to the centre above it, peaking at its own. */
    assert_true(cloud_lo > 74.0 && cloud_hi < 276.0);
    struct reference_rng rng;
    reference_rng_seed(&rng, 1, 0);
    double tr = 0.0;
    int paths = 200000;
    for (int i = 0; i < paths; i++)
        tr += reference_transmittance(ref, (const double[3]){2500.0, 3500.0, 6000.0},
                                      (const double[3]){0.0, 0.0, -1.0}, 0.0, 1e4, &rng);
    tr /= paths;
    print_message("%s: tau %.4f, reference T %.5f, e^-tau %.5f\n", what, tau, tr, exp(-tau));
    assert_true(fabs(tr - exp(-tau)) < 1e-3);
    reference_destroy(ref);
}

static void test_native_keeps_the_layer(void **state)
{
    (void)state;
    struct field_volume fv;
    struct ext_volume ev;
    read_layer(true, &fv, &ev);
    const struct grid3 *g = &fv.grid;
    assert_int_equal(g->n[2], THIN_LAYER_LEVELS);
    assert_true(grid3_stretched(g));
    for (int k = 0; k < THIN_LAYER_LEVELS; k++) /* the model's levels, where it put them */
        assert_true(fabs(g->z_centre[k] - 0.5 * (THIN_LAYER_FACES[k] + THIN_LAYER_FACES[k + 1])) <
                    1e-2);
    size_t plane = 36;
    for (int k = 0; k < THIN_LAYER_LEVELS; k++)
        assert_true(fv.q[SPECIES_CLOUD][plane * k + 7] ==
                    (k == THIN_LAYER_LEVEL ? (float)THIN_LAYER_Q : 0.0f));
    double tau = layer_tau(&ev);
    assert_true(tau > 0.5 && tau < 4.0);

    reference_keeps_the_layer(&ev, tau, "native");

    /* On 439 m uniform levels the layer is smeared over the lowest cell and the next: the
     * optical depth up a column is far from the file's. */
    struct field_volume fu;
    struct ext_volume eu;
    read_layer(false, &fu, &eu);
    assert_true(fabs(fu.grid.spacing[2] - THIN_LAYER_HEIGHT_M / 14.0) < 0.01); /* PHB in float */
    double su = column_tau(&eu);
    print_message("uniform 439 m: tau %.4f (file %.4f)\n", su, tau);
    assert_true(fabs(su - tau) > 0.2 * tau);
    field_volume_finish(&fu);
    ext_volume_finish(&eu);
    field_volume_finish(&fv);
    ext_volume_finish(&ev);
}

/* The thin layer in CM1's and CF's convention: on the file's own levels (the default) the
 * grid's levels are the file's and every value is the file's at its level (no column
 * resampled); the layer keeps its optical depth, which the even levels lose; even levels stay
 * a plain uniform grid; the data source's grid is the step's, height exaggeration included. */
static void test_hgrid_native_levels(void **state)
{
    (void)state;
    for (int kind = HGRID_CM1; kind <= HGRID_CF; kind++) {
        const char *path = test_tmp_path(kind == HGRID_CM1 ? "thin_cm1.nc" : "thin_cf.nc");
        assert_true(thin_layer_write_hgrid(path, (enum hgrid_kind)kind));
        const char *files[] = {path};
        struct hgrid *h = (kind == HGRID_CM1 ? cm1_open : cf_open)(files, 1, 1024.0);
        assert_non_null(h);
        assert_true(hgrid_get_meta(h)->stretched);
        assert_true(hgrid_native(h, true) && !hgrid_native(h, false));
        struct grid3 g;
        hgrid_grid(h, true, &g);
        struct hgrid_desc hd = {.memory_mb = 1024.0, .qvapor = true, .native_levels = true};
        struct field_volume fv;
        assert_true(hgrid_read_step(h, 0, &hd, &fv, NULL));
        assert_true(grid3_equal(&g, &fv.grid)); /* hgrid_grid repeats the step's grid */
        assert_true(grid3_stretched(&fv.grid));
        assert_int_equal(fv.grid.n[2], THIN_LAYER_LEVELS);
        assert_true(fabs(fv.grid.origin[2]) < 1e-3 &&
                     fabs(fv.grid.origin[2] + THIN_LAYER_LEVELS * fv.grid.spacing[2] -
                          THIN_LAYER_HEIGHT_M) < 1e-2);
        size_t plane = 36;
        for (int k = 0; k < THIN_LAYER_LEVELS; k++) {
            /* The file's heights (CM1's in km as float) and its values, copied. */
            assert_true(fabs(fv.grid.z_centre[k] - 0.5 * (THIN_LAYER_FACES[k] +
                                                          THIN_LAYER_FACES[k + 1])) < 1e-2);
            assert_true(fv.grid.z_centre[k] == hgrid_get_meta(h)->z[k]);
            for (size_t c = 0; c < plane; c++) {
                assert_true(fv.qvapor[plane * k + c] == (float)((k + 1) * 1e-4));
                assert_true(fv.q[SPECIES_CLOUD][plane * k + c] ==
                            (k == THIN_LAYER_LEVEL ? (float)THIN_LAYER_Q : 0.0f));
            }
        }
        struct optics_params optics;
        optics_params_defaults(&optics);
        struct species_select sel;
        species_select_defaults(&sel);
        struct ext_volume ev;
        assert_true(ext_volume_from_fields(&fv, &optics, &sel, &ev));
        double tau = layer_tau(&ev);
        assert_true(tau > 0.5 && tau < 4.0);
        reference_keeps_the_layer(&ev, tau, kind == HGRID_CM1 ? "CM1 native" : "CF native");

        /* data.vertical = "uniform": 12 even levels of 512 m, the layer smeared. */
        hd.native_levels = false;
        struct field_volume fu;
        struct ext_volume eu;
        assert_true(hgrid_read_step(h, 0, &hd, &fu, NULL));
        assert_false(grid3_stretched(&fu.grid));
        assert_true(fabs(fu.grid.spacing[2] - THIN_LAYER_HEIGHT_M / THIN_LAYER_LEVELS) < 0.01);
        assert_true(ext_volume_from_fields(&fu, &optics, &sel, &eu));
        double su = column_tau(&eu);
        print_message("uniform 512 m: tau %.4f (file %.4f)\n", su, tau);
        assert_true(fabs(su - tau) > 0.2 * tau);
        assert_true(ext_volume_max_beta(&eu) < 0.5 * ext_volume_max_beta(&ev));

        /* Through the data source (data_source_grid is the grid the steps load onto), with
         * the heights exaggerated twice. */
        struct data_source_desc sd = {.format = kind == HGRID_CM1 ? DATA_SOURCE_CM1
                                                                  : DATA_SOURCE_CF,
                                      .files = files, .file_count = 1, .height_scale = 2.0};
        wrf_desc_defaults(&sd.wrf);
        sd.wrf.native_levels = true;
        optics_params_defaults(&sd.optics);
        species_select_defaults(&sd.select);
        struct data_source *src = data_source_open(&sd);
        assert_non_null(src);
        struct grid3 sg;
        assert_true(data_source_grid(src, &sg));
        struct ext_volume es;
        assert_true(data_source_load(src, 0, &es, NULL, NULL));
        assert_true(grid3_equal(&sg, &es.grid));
        assert_true(grid3_stretched(&sg));
        for (int k = 0; k < THIN_LAYER_LEVELS; k++)
            assert_true(sg.z_centre[k] == 2.0 * fv.grid.z_centre[k]);
        /* The column keeps its optical depth (the stretch moves the medium). */
        size_t v = plane * THIN_LAYER_LEVEL + 2 + 6 * 3;
        assert_true(fabs((es.beta[2 * v] + es.beta[2 * v + 1]) * 2.0 * 100.0 - tau) <
                    1e-5 * tau);
        ext_volume_finish(&es);
        data_source_close(src);

        ext_volume_finish(&eu);
        field_volume_finish(&fu);
        ext_volume_finish(&ev);
        field_volume_finish(&fv);
        hgrid_close(h);
    }

    /* Even levels stay a plain uniform grid on "native" too. */
    const char *path = test_tmp_path("even_cm1.nc");
    struct grid3 g = {.n = {4, 4, 5}, .spacing = {1000.0, 1000.0, 200.0}};
    struct field_volume v = {.grid = g};
    v.q[SPECIES_CLOUD] = calloc(grid3_count(&g), sizeof(float));
    assert_non_null(v.q[SPECIES_CLOUD]);
    struct hgrid_writer *w = hgrid_writer_create(path, &g, &(struct hgrid_write_desc){0});
    assert_true(w && hgrid_writer_add(w, &v, 0.0) && hgrid_writer_finish(w));
    field_volume_finish(&v);
    const char *files[] = {path};
    struct hgrid *h = cm1_open(files, 1, 1024.0);
    assert_non_null(h);
    assert_false(hgrid_native(h, true));
    struct grid3 eg;
    hgrid_grid(h, true, &eg);
    assert_false(grid3_stretched(&eg));
    assert_true(fabs(eg.spacing[2] - 200.0) < 1e-3);
    hgrid_close(h);
}

/* An extinction file written from the model's levels reads back on the same levels. */
static void test_extinction_file_keeps_the_levels(void **state)
{
    (void)state;
    struct field_volume fv;
    struct ext_volume ev, back;
    read_layer(true, &fv, &ev);
    const char *path = test_tmp_path("thin-ext.nc");
    struct extfile_writer *w = extfile_writer_create(path, &ev.grid, "test", "test", NULL);
    assert_non_null(w);
    assert_true(extfile_writer_add(w, &ev, "2005-08-28_00:00:00"));
    assert_true(extfile_writer_finish(w));
    struct extfile *f = extfile_open(path, 0.0);
    assert_non_null(f);
    const struct grid3 *g = extfile_grid(f);
    assert_true(grid3_stretched(g));
    assert_int_equal(g->n[2], ev.grid.n[2]);
    assert_true(fabs(g->origin[2] - ev.grid.origin[2]) < 1e-6);
    assert_true(fabs(g->spacing[2] - ev.grid.spacing[2]) < 1e-6);
    for (int k = 0; k < g->n[2]; k++)
        assert_true(fabs(g->z_centre[k] - ev.grid.z_centre[k]) < 1e-6);
    assert_true(extfile_read_step(f, 0, &back, NULL));
    assert_memory_equal(back.beta, ev.beta, 2 * grid3_count(&ev.grid) * sizeof(float));
    extfile_close(f);
    ext_volume_finish(&back);
    field_volume_finish(&fv);
    ext_volume_finish(&ev);
}

/* A parent and its nest on uneven levels of their own (the nest's 3 % higher), a field linear
 * in height: on the model's own levels both are read onto the parent's (the nest's values
 * there, not at its own heights), and the composite is on them. */
static void test_nest_on_the_parents_levels(void **state)
{
    (void)state;
    const double faces[7] = {0.0, 60.0, 150.0, 300.0, 600.0, 1200.0, 3000.0};
    double zp[6], zn[6];
    for (int k = 0; k < 6; k++) {
        zp[k] = 0.5 * (faces[k] + faces[k + 1]);
        zn[k] = 1.03 * zp[k];
    }
    struct grid3 pg = {.n = {12, 12, 0}, .spacing = {3000.0, 3000.0, 0.0}};
    struct grid3 ng = {.n = {12, 12, 0}, .spacing = {1000.0, 1000.0, 0.0}};
    assert_true(grid3_set_levels(&pg, zp, 6, 0.0, 3000.0));
    assert_true(grid3_set_levels(&ng, zn, 6, 0.0, 3090.0));
    double ex = 12 * 3000.0;
    struct wrf_write_desc pd = {.cen_lat = 25.0, .cen_lon = -89.0, .grid_id = 1, .parent_id = 1,
                                .i_parent_start = 1, .j_parent_start = 1,
                                .parent_grid_ratio = 1, .map_corner_m = {-0.5 * ex, -0.5 * ex}};
    struct wrf_write_desc nd = pd;
    nd.grid_id = 2;
    nd.i_parent_start = 5;
    nd.j_parent_start = 5;
    nd.parent_grid_ratio = 3;
    nd.map_corner_m[0] += 4 * 3000.0;
    nd.map_corner_m[1] += 4 * 3000.0;
    char a[512], b[512];
    snprintf(a, sizeof(a), "%s", test_tmp_path("lv_d01.nc"));
    snprintf(b, sizeof(b), "%s", test_tmp_path("lv_d02.nc"));
    const struct grid3 *grids[2] = {&pg, &ng};
    const struct wrf_write_desc *descs[2] = {&pd, &nd};
    const char *paths[2] = {a, b};
    for (int d = 0; d < 2; d++) {
        struct field_volume fv = {.grid = *grids[d]};
        size_t n = grid3_count(grids[d]);
        fv.q[SPECIES_CLOUD] = calloc(n, sizeof(float));
        size_t plane = 144; /* linear in height, the nest's 1e-4 more */
        for (size_t i = 0; i < n; i++)
            fv.q[SPECIES_CLOUD][i] =
                (float)(1e-7 * grids[d]->z_centre[i / plane] + (d ? 1e-4 : 0.0));
        struct wrf_writer *w = wrf_writer_create(paths[d], grids[d], descs[d]);
        assert_non_null(w);
        assert_true(wrf_writer_add(w, &fv, "2005-08-28_12:00:00"));
        assert_true(wrf_writer_finish(w));
        field_volume_finish(&fv);
    }
    bool single = true;
    struct nest_set *set = nest_open(paths, 2, 0.0, &single);
    assert_non_null(set);
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    d.native_levels = true;
    struct field_volume out;
    log_set_level(LOG_ERROR);
    assert_true(nest_read_step(set, 0, &d, &out, NULL));
    log_set_level(LOG_INFO);
    assert_true(grid3_stretched(&out.grid));
    for (int k = 0; k < 6; k++)
        assert_true(fabs(out.grid.z_centre[k] - zp[k]) < 0.05);
    /* Inside the nest its own value (read onto the parent's levels), outside the parent's. */
    size_t plane = (size_t)out.grid.n[0] * out.grid.n[1];
    float inside = out.q[SPECIES_CLOUD][plane * 3 + grid3_index(&out.grid, 18, 18, 0)];
    float outside = out.q[SPECIES_CLOUD][plane * 3 + grid3_index(&out.grid, 2, 2, 0)];
    print_message("level 3 at %.1f m: nest %.4g (expected %.4g), parent %.4g (expected %.4g)\n",
                  zp[3], (double)inside, 1e-7 * zp[3] + 1e-4, (double)outside, 1e-7 * zp[3]);
    assert_true(fabs(inside - (1e-7 * zp[3] + 1e-4)) < 1e-8);
    assert_true(fabs(outside - 1e-7 * zp[3]) < 1e-8);
    field_volume_finish(&out);
    nest_close(set);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mapping),
        cmocka_unit_test(test_native_keeps_the_layer),
        cmocka_unit_test(test_hgrid_native_levels),
        cmocka_unit_test(test_extinction_file_keeps_the_levels),
        cmocka_unit_test(test_nest_on_the_parents_levels),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
