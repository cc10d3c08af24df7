/* Placing the storm on the earth: the XLAT/XLONG inverse, GSHHG coastlines, the terrain height
 * field, and what happens when a piece is missing. */
#include "testutil.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "data/coast.h"
#include "data/geo.h"
#include "data/terrain.h"
#include "data/wrf.h"

#define KATRINA "wrf/katrina_2005_mercator_wsm3.nc"
#define LAMBERT "wrf/lambert_thompson_cropped.nc"

static struct wrf *open_one(const char *shared_name)
{
    const char *path = test_shared_data(shared_name);
    return wrf_open(&path, 1, 0.0);
}

static void grid_map(const struct wrf_meta *m, struct geo_map *g)
{
    assert_true(geo_map_init_grid(g, m->xlat, m->xlong, m->nx, m->ny, m->dx, m->dy));
}

/* The column whose XLAT/XLONG is nearest (brute force over every column), and its distance
 * in degrees (longitude scaled by cos lat). */
static double nearest_column(const struct wrf_meta *m, double lat, double lon, int *ci, int *cj)
{
    double best = INFINITY;
    for (int j = 0; j < m->ny; j++) {
        for (int i = 0; i < m->nx; i++) {
            size_t k = (size_t)j * m->nx + i;
            double a = m->xlat[k] - lat, b = (m->xlong[k] - lon) * cos(lat * M_PI / 180.0);
            if (a * a + b * b < best) {
                best = a * a + b * b;
                *ci = i;
                *cj = j;
            }
        }
    }
    return sqrt(best);
}

static void test_columns_map_to_their_centres(void **state)
{
    /* Every column's own lat/lon lands on its centre ((i + 0.5) DX, (j + 0.5) DY), on the
     * Mercator and on the (curved) Lambert grid. */
    const char *names[2] = {KATRINA, LAMBERT};
    for (int f = 0; f < 2; f++) {
        struct wrf *w = open_one(names[f]);
        assert_non_null(w);
        const struct wrf_meta *m = wrf_get_meta(w);
        struct geo_map g;
        grid_map(m, &g);
        for (int j = 0; j < m->ny; j++) {
            for (int i = 0; i < m->nx; i++) {
                size_t k = (size_t)j * m->nx + i;
                double x, y;
                assert_true(geo_map_to_frame(&g, m->xlat[k], m->xlong[k], &x, &y));
                assert_float_equal(x, (i + 0.5) * m->dx, 1.0); /* metres */
                assert_float_equal(y, (j + 0.5) * m->dy, 1.0);
            }
        }
        /* And back, between columns too. */
        for (double fy = 0.1; fy < m->ny * m->dy; fy += m->dy * 0.77) {
            for (double fx = 0.1; fx < m->nx * m->dx; fx += m->dx * 0.61) {
                double lat, lon, x, y;
                assert_true(geo_map_to_latlon(&g, fx, fy, &lat, &lon));
                assert_true(geo_map_to_frame(&g, lat, lon, &x, &y));
                assert_float_equal(x, fx, 0.5);
                assert_float_equal(y, fy, 0.5);
            }
        }
        geo_map_finish(&g);
        wrf_close(w);
    }
}

static void test_katrina_coastline_lands_where_xlat_xlong_say(void **state)
{
    struct wrf *w = open_one(KATRINA);
    assert_non_null(w);
    const struct wrf_meta *m = wrf_get_meta(w);
    struct geo_map g;
    grid_map(m, &g);

    /* The mouth of the Mississippi (29.15 N, 89.25 W) is NOT in the Katrina sample: the domain
     * spans 21.80 to 25.67 N.  The inverse puts it about 3.5 degrees (~40 rows of 10 km) north
     * of the last row, extrapolated. */
    double ij[2];
    assert_true(m->lat_max < 29.15);
    assert_true(geo_map_grid_index(&g, 29.15, -89.25, ij));
    assert_true(ij[1] > m->ny - 1 + 30 && ij[1] < m->ny - 1 + 50);

    /* Inside the domain GSHHG has the islands of Arrecife Alacranes (22.4 N, 89.7 W) in the
     * intermediate resolution: every coastline vertex there lands within one grid cell of the
     * column that XLAT/XLONG say is nearest, and the grid at that position gives the vertex's
     * lat/lon back. */
    const double box[4] = {m->lat_min, m->lat_max, m->lon_min, m->lon_max};
    struct coast_lines c;
    assert_true(coast_read(coast_file('i'), box, COAST_LAND, &c));
    int checked = 0;
    for (int p = 0; p < c.n_points; p++) {
        double x, y;
        if (c.lat[p] < box[0] || c.lat[p] > box[1] || c.lon[p] < box[2] || c.lon[p] > box[3])
            continue;
        assert_true(geo_map_to_frame(&g, c.lat[p], c.lon[p], &x, &y));
        double fi = x / m->dx - 0.5, fj = y / m->dy - 0.5;
        int ci = -1, cj = -1;
        double dist = nearest_column(m, c.lat[p], c.lon[p], &ci, &cj);
        assert_true(dist < 0.1); /* degrees: the point is among the columns */
        assert_true(fabs(fi - ci) <= 1.0 && fabs(fj - cj) <= 1.0);
        double lat, lon;
        assert_true(geo_map_to_latlon(&g, x, y, &lat, &lon));
        assert_float_equal(lat, c.lat[p], 1e-5);
        assert_float_equal(lon, c.lon[p], 1e-5);
        /* Alacranes: around column 20, row 6. */
        assert_true(fi > 15 && fi < 25 && fj > 3 && fj < 10);
        checked++;
    }
    assert_true(checked >= 4);
    coast_lines_finish(&c);

    /* The offset moves the data east/north on the map: map positions move the other way. */
    double x0, y0, x1, y1;
    assert_true(geo_map_to_frame(&g, 23.0, -89.0, &x0, &y0));
    g.offset[0] = 12e3;
    g.offset[1] = -5e3;
    assert_true(geo_map_to_frame(&g, 23.0, -89.0, &x1, &y1));
    assert_float_equal(x1, x0 - 12e3, 1e-6);
    assert_float_equal(y1, y0 + 5e3, 1e-6);
    geo_map_finish(&g);
    wrf_close(w);
}

static void test_coastlines_of_florida(void **state)
{
    /* The low resolution has Florida's Atlantic coast near Jacksonville (30 to 30.8 N, 81.4 W):
     * a check of the bin layout (bins counted from 0 E and from the north pole). */
    const double box[4] = {29.9, 30.8, -81.7, -81.2};
    struct coast_lines c;
    assert_true(coast_read(coast_file('l'), box, COAST_LAND, &c));
    assert_true(c.n_lines >= 1);
    int inside = 0;
    for (int p = 0; p < c.n_points; p++) {
        if (c.lat[p] >= box[0] && c.lat[p] <= box[1] && c.lon[p] >= box[2] && c.lon[p] <= box[3])
            inside++;
        assert_true(c.lon[p] > -82.5 && c.lon[p] < -80.5); /* shifted next to the box */
    }
    assert_true(inside >= 1);
    coast_lines_finish(&c);
    /* The same box in 0..360 longitudes. */
    const double box360[4] = {29.9, 30.8, 278.3, 278.8};
    assert_true(coast_read(coast_file('l'), box360, COAST_LAND, &c));
    assert_true(c.n_lines >= 1 && c.lon[0] > 277.5 && c.lon[0] < 279.5);
    coast_lines_finish(&c);
}

static void test_missing_or_wrong_coastline_file(void **state)
{
    const double box[4] = {20, 30, -95, -80};
    struct coast_lines c;
    assert_false(coast_read(test_tmp_path("no_such_gshhg.nc"), box, 1, &c));
    assert_int_equal(c.n_lines, 0);
    assert_null(c.lat);
    /* A NetCDF file that is not GSHHG. */
    assert_false(coast_read(test_shared_data(KATRINA), box, 1, &c));
    assert_int_equal(c.n_points, 0);
    /* Not NetCDF at all. */
    assert_false(coast_read(test_write_file("junk.nc", "not a netcdf file\n"), box, 1, &c));
    coast_lines_finish(&c);
    coast_lines_finish(NULL);
}

static void test_local_origin(void **state)
{
    /* Without XLAT/XLONG: Mercator true at the origin's latitude on WRF's sphere. */
    struct geo_map g;
    geo_map_init_local(&g, 25.0, -80.0);
    double x, y;
    assert_true(geo_map_to_frame(&g, 25.0, -80.0, &x, &y));
    assert_float_equal(x, 0.0, 1e-6);
    assert_float_equal(y, 0.0, 1e-6);
    assert_true(geo_map_to_frame(&g, 25.0, -79.0, &x, &y));
    assert_float_equal(x, GEO_EARTH_RADIUS_M * cos(25.0 * M_PI / 180.0) * M_PI / 180.0, 1e-3);
    /* Near the origin a degree of latitude is R pi / 180 long. */
    assert_true(geo_map_to_frame(&g, 25.01, -80.0, &x, &y));
    assert_float_equal(y, GEO_EARTH_RADIUS_M * 0.01 * M_PI / 180.0, 2.0);
    double lat, lon;
    assert_true(geo_map_to_latlon(&g, 123e3, -456e3, &lat, &lon));
    assert_true(geo_map_to_frame(&g, lat, lon, &x, &y));
    assert_float_equal(x, 123e3, 1e-3);
    assert_float_equal(y, -456e3, 1e-3);
    geo_map_finish(&g);
    /* No map: nothing is placed. */
    assert_false(geo_map_to_frame(&g, 25.0, -80.0, &x, &y));
}

static void test_bad_grid(void **state)
{
    float lat[4] = {20, 20, 21, NAN}, lon[4] = {-90, -89, -90, -89};
    struct geo_map g;
    assert_false(geo_map_init_grid(&g, lat, lon, 2, 2, 1e4, 1e4));
    assert_null(g.lat);
    assert_false(geo_map_init_grid(&g, lat, lon, 1, 4, 1e4, 1e4));
}

static void test_terrain_from_hgt_and_landmask(void **state)
{
    struct wrf *w = open_one(LAMBERT);
    assert_non_null(w);
    const struct wrf_meta *m = wrf_get_meta(w);
    assert_non_null(m->lu_index);
    assert_string_equal(m->land_use, "USGS");
    struct grid3 box = {.n = {10, 8, 27}, .spacing = {30e3, 30e3, 770.9}};
    struct terrain t;
    assert_true(terrain_from_wrf(m, &box, &t));
    /* Every column plus the two faces per axis. */
    assert_int_equal(t.nx, 12);
    assert_int_equal(t.ny, 10);
    assert_float_equal(t.x[0], 0.0, 1e-9);
    assert_float_equal(t.x[11], 300e3, 1e-9);
    assert_float_equal(t.x[1], 15e3, 1e-9);
    /* Heights from ncdump: HGT(0, 0) = 4798.562, HGT(9, 7) = 4984.282; the faces repeat. */
    assert_float_equal(t.height[1 * 12 + 1], 4798.562, 1e-3);
    assert_float_equal(t.height[0], 4798.562, 1e-3);
    assert_float_equal(t.height[8 * 12 + 10], 4984.282, 1e-3);
    assert_float_equal(terrain_height_at(&t, 15e3, 15e3), 4798.562, 1e-3);
    /* Between two columns: linear. */
    assert_float_equal(terrain_height_at(&t, 30e3, 15e3), 0.5 * (4798.562 + 4878.048), 1e-2);
    /* LANDMASK has one water column, the first of the last row. */
    assert_int_equal(t.kind[8 * 12 + 1], TERRAIN_SEA);
    assert_int_not_equal(t.kind[8 * 12 + 2], TERRAIN_SEA);
    assert_true(t.has_landmask && t.has_land_use);
    terrain_finish(&t);
    terrain_finish(NULL);

    /* A cropped box starting at column 3 covers columns 3..6. */
    struct grid3 crop = {.n = {4, 2, 5}, .spacing = {30e3, 30e3, 1e3}, .origin = {90e3, 60e3, 0}};
    assert_true(terrain_from_wrf(m, &crop, &t));
    assert_int_equal(t.nx, 6);
    assert_int_equal(t.ny, 4);
    assert_float_equal(t.x[1], 105e3, 1e-9);
    assert_float_equal(t.height[1 * 6 + 1], 5161.611, 1e-3); /* row 2, column 3 */
    terrain_finish(&t);
    wrf_close(w);
}

static void test_terrain_without_landmask_or_hgt(void **state)
{
    /* Katrina has HGT (all sea, 0 m) but no LANDMASK and no LU_INDEX: land is HGT > 0.5 m. */
    struct wrf *w = open_one(KATRINA);
    assert_non_null(w);
    const struct wrf_meta *m = wrf_get_meta(w);
    assert_null(m->landmask);
    struct grid3 box = {.n = {48, 48, 14}, .spacing = {10e3, 10e3, 439.3}};
    struct terrain t;
    assert_true(terrain_from_wrf(m, &box, &t));
    assert_false(t.has_landmask);
    for (int i = 0; i < t.nx * t.ny; i++)
        assert_int_equal(t.kind[i], TERRAIN_SEA);
    terrain_finish(&t);

    /* No HGT: no terrain (the caller keeps the flat ground); the struct stays empty. */
    struct wrf_meta copy = *m;
    copy.hgt = NULL;
    assert_false(terrain_from_wrf(&copy, &box, &t));
    assert_null(t.height);
    /* A box beside the grid covers no column. */
    struct grid3 away = box;
    away.origin[0] = 1e7;
    assert_false(terrain_from_wrf(m, &away, &t));
    wrf_close(w);
}

static void test_land_use_and_albedo(void **state)
{
    assert_int_equal(terrain_kind_of_land_use("USGS", 16), TERRAIN_SEA);
    assert_int_equal(terrain_kind_of_land_use("USGS", 24), TERRAIN_ICE);
    assert_int_equal(terrain_kind_of_land_use("USGS", 14), TERRAIN_FOREST);
    assert_int_equal(terrain_kind_of_land_use("MODIFIED_IGBP_MODIS_NOAH", 17), TERRAIN_SEA);
    assert_int_equal(terrain_kind_of_land_use("MODIFIED_IGBP_MODIS_NOAH", 15), TERRAIN_ICE);
    assert_int_equal(terrain_kind_of_land_use("USGS", 99), TERRAIN_LAND);
    float sea[3], low[3], high[3], peak[3];
    terrain_albedo(TERRAIN_SEA, 0.0, sea);
    terrain_albedo(TERRAIN_FOREST, 100.0, low);
    terrain_albedo(TERRAIN_FOREST, 3500.0, high);
    terrain_albedo(TERRAIN_FOREST, 6000.0, peak);
    assert_true(sea[2] > sea[0]);                          /* blue */
    assert_true(low[1] > low[0] && low[1] > low[2]);       /* green */
    assert_true(high[0] > low[0]);                         /* toward rock */
    assert_true(peak[0] > 0.6f && peak[2] > 0.6f);         /* snow */
    for (int c = 0; c < 3; c++)
        assert_true(sea[c] >= 0.0f && peak[c] <= 1.0f);
}

int main(void)
{
    log_set_level(LOG_NONE);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_columns_map_to_their_centres),
        cmocka_unit_test(test_katrina_coastline_lands_where_xlat_xlong_say),
        cmocka_unit_test(test_coastlines_of_florida),
        cmocka_unit_test(test_missing_or_wrong_coastline_file),
        cmocka_unit_test(test_local_origin),
        cmocka_unit_test(test_bad_grid),
        cmocka_unit_test(test_terrain_from_hgt_and_landmask),
        cmocka_unit_test(test_terrain_without_landmask_or_hgt),
        cmocka_unit_test(test_land_use_and_albedo),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
