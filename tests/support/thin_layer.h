/*
 * A synthetic WRF file with a known thin cloud layer on the model's own uneven levels, for the
 * native-levels tests (tests/unit/test_levels.c, tests/gl/test_levels.c): 6 x 6 columns of
 * 1 km over the sea, 12 levels whose faces are THIN_LAYER_FACES (the lowest 50, 50, 100, 150 m
 * thick, the highest 1146 m), cloud water THIN_LAYER_Q only in level 2, between 100 and 200 m.
 * The box is 6146 m tall: 14 uniform levels of it are 439 m, Katrina's.
 */
#ifndef ANVIL_TEST_THIN_LAYER_H
#define ANVIL_TEST_THIN_LAYER_H

#include <stdlib.h>

#include "data/hgrid_write.h"
#include "data/wrf_write.h"

#define THIN_LAYER_LEVELS 12
#define THIN_LAYER_LEVEL 2          /* the cloudy level */
#define THIN_LAYER_BOTTOM_M 100.0
#define THIN_LAYER_TOP_M 200.0
#define THIN_LAYER_Q 1e-4           /* kg/kg of cloud water there */
#define THIN_LAYER_HEIGHT_M 6146.0  /* the model top */
static const double THIN_LAYER_FACES[THIN_LAYER_LEVELS + 1] = {
    0.0, 50.0, 100.0, 200.0, 350.0, 600.0, 1000.0, 1500.0, 2200.0, 3000.0, 4000.0, 5000.0,
    THIN_LAYER_HEIGHT_M};

/* Writes the file to PATH; false when it cannot be written. */
static inline bool thin_layer_write(const char *path)
{
    struct grid3 g = {.n = {6, 6, 0}, .spacing = {1000.0, 1000.0, 0.0}};
    double zc[THIN_LAYER_LEVELS];
    for (int k = 0; k < THIN_LAYER_LEVELS; k++)
        zc[k] = 0.5 * (THIN_LAYER_FACES[k] + THIN_LAYER_FACES[k + 1]);
    if (!grid3_set_levels(&g, zc, THIN_LAYER_LEVELS, 0.0, THIN_LAYER_HEIGHT_M))
        return false;
    struct field_volume v = {.grid = g};
    size_t plane = 36, n = plane * THIN_LAYER_LEVELS;
    v.q[SPECIES_CLOUD] = calloc(n, sizeof(float));
    if (!v.q[SPECIES_CLOUD])
        return false;
    for (size_t c = 0; c < plane; c++)
        v.q[SPECIES_CLOUD][plane * THIN_LAYER_LEVEL + c] = (float)THIN_LAYER_Q;
    struct wrf_writer *w = wrf_writer_create(path, &g, &(struct wrf_write_desc){.cen_lat = 25.0,
                                                                                .cen_lon = -85.0});
    bool ok = w && wrf_writer_add(w, &v, "2005-08-28_00:00:00");
    if (ok)
        ok = wrf_writer_finish(w); /* frees W */
    else
        wrf_writer_destroy(w);
    field_volume_finish(&v);
    return ok;
}

/* The same layer in CM1's or CF's convention (data/hgrid_write.h): its levels the same
 * centres, its faces half way between them; level k's vapour is (k + 1) 1e-4 kg/kg, so a
 * reader's values show which level they came from. */
static inline bool thin_layer_write_hgrid(const char *path, enum hgrid_kind kind)
{
    struct grid3 g = {.n = {6, 6, 0}, .spacing = {1000.0, 1000.0, 0.0}};
    double zc[THIN_LAYER_LEVELS];
    for (int k = 0; k < THIN_LAYER_LEVELS; k++)
        zc[k] = 0.5 * (THIN_LAYER_FACES[k] + THIN_LAYER_FACES[k + 1]);
    if (!grid3_set_levels(&g, zc, THIN_LAYER_LEVELS, 0.0, THIN_LAYER_HEIGHT_M))
        return false;
    struct field_volume v = {.grid = g};
    size_t plane = 36, n = plane * THIN_LAYER_LEVELS;
    v.q[SPECIES_CLOUD] = calloc(n, sizeof(float));
    v.qvapor = calloc(n, sizeof(float));
    if (!v.q[SPECIES_CLOUD] || !v.qvapor) {
        field_volume_finish(&v);
        return false;
    }
    for (size_t c = 0; c < plane; c++) {
        v.q[SPECIES_CLOUD][plane * THIN_LAYER_LEVEL + c] = (float)THIN_LAYER_Q;
        for (int k = 0; k < THIN_LAYER_LEVELS; k++)
            v.qvapor[plane * k + c] = (float)((k + 1) * 1e-4);
    }
    struct hgrid_writer *w = hgrid_writer_create(path, &g, &(struct hgrid_write_desc){.kind = kind});
    bool ok = w && hgrid_writer_add(w, &v, 0.0);
    if (ok)
        ok = hgrid_writer_finish(w); /* frees W */
    else
        hgrid_writer_destroy(w);
    field_volume_finish(&v);
    return ok;
}

#endif
