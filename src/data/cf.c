#include "data/cf.h"

#include <stdio.h>
#include <string.h>

#include <netcdf.h>

#include "common/log.h"
#include "data/nclock.h"
#include "data/ncopen.h"

/* CF standard names (CF standard name table) in enum hgrid_var order. */
static const char *const standard[HGRID_VAR_COUNT] = {
    "mass_fraction_of_cloud_liquid_water_in_air",
    "mass_fraction_of_rain_in_air",
    "mass_fraction_of_cloud_ice_in_air",
    "mass_fraction_of_snow_in_air",
    "mass_fraction_of_graupel_in_air",
    "specific_humidity",
    "air_temperature",
    "air_potential_temperature",
    "air_pressure",
    "air_density",
    "eastward_wind",
    "northward_wind",
    "upward_air_velocity",
};

const char *cf_standard_name(enum hgrid_var v)
{
    return (v >= 0 && v < HGRID_VAR_COUNT) ? standard[v] : NULL;
}

static bool text_att(int ncid, int varid, const char *name, char *buf, size_t size)
{
    size_t len;
    nc_type t;
    buf[0] = '\0';
    if (nc_inq_att(ncid, varid, name, &t, &len) != NC_NOERR || t != NC_CHAR || len >= size ||
        nc_get_att_text(ncid, varid, name, buf) != NC_NOERR)
        return false;
    buf[len] = '\0';
    return true;
}

enum axis_kind { AXIS_NONE = -1, AXIS_X, AXIS_Y, AXIS_Z, AXIS_T };

/* What 1-D variable VARID is as a coordinate; *LATLON set for degrees. */
static enum axis_kind axis_of(int ncid, int varid, bool *degrees)
{
    int nd;
    if (nc_inq_varndims(ncid, varid, &nd) != NC_NOERR || nd != 1)
        return AXIS_NONE;
    char axis[16], sn[128], units[128], positive[16];
    text_att(ncid, varid, "axis", axis, sizeof(axis));
    text_att(ncid, varid, "standard_name", sn, sizeof(sn));
    text_att(ncid, varid, "units", units, sizeof(units));
    bool has_positive = text_att(ncid, varid, "positive", positive, sizeof(positive));
    *degrees = !strncmp(units, "degree", 6);
    if (!strcmp(axis, "T") || !strcmp(sn, "time") || strstr(units, " since "))
        return AXIS_T;
    if (!strcmp(axis, "Z") || has_positive || !strcmp(sn, "height") ||
        !strcmp(sn, "altitude") || !strcmp(sn, "height_above_mean_sea_level"))
        return AXIS_Z;
    if (!strcmp(axis, "X") || !strcmp(sn, "projection_x_coordinate") ||
        !strcmp(sn, "longitude") || !strcmp(sn, "grid_longitude") ||
        !strcmp(units, "degrees_east") || !strcmp(units, "degree_east"))
        return AXIS_X;
    if (!strcmp(axis, "Y") || !strcmp(sn, "projection_y_coordinate") ||
        !strcmp(sn, "latitude") || !strcmp(sn, "grid_latitude") ||
        !strcmp(units, "degrees_north") || !strcmp(units, "degree_north"))
        return AXIS_Y;
    return AXIS_NONE;
}

/* Finds the coordinates: 1-D variables named as their dimension (or carrying an axis). */
static bool find_axes(int ncid, const char *path, struct hgrid_layout *l, bool quiet)
{
    int nvars;
    nc_inq_nvars(ncid, &nvars);
    bool degrees[3] = {false, false, false};
    for (int id = 0; id < nvars; id++) {
        bool deg = false;
        enum axis_kind k = axis_of(ncid, id, &deg);
        if (k == AXIS_NONE)
            continue;
        int dim;
        nc_inq_vardimid(ncid, id, &dim);
        if (k == AXIS_T) {
            if (l->time_var < 0) {
                l->time_var = id;
                l->time_dim = dim;
            }
            continue;
        }
        if (l->axis_var[k] >= 0) {
            /* Of several vertical coordinates (a 2 m or 10 m level beside the levels) the one
             * with the most levels. */
            size_t have, len;
            nc_inq_dimlen(ncid, l->axis_dim[k], &have);
            nc_inq_dimlen(ncid, dim, &len);
            if (k != AXIS_Z || len <= have)
                continue;
        }
        l->axis_var[k] = id;
        l->axis_dim[k] = dim;
        degrees[k] = deg;
    }
    static const char *const what[3] = {
        "x coordinate (axis = \"X\", projection_x_coordinate or longitude)",
        "y coordinate (axis = \"Y\", projection_y_coordinate or latitude)",
        "vertical coordinate (axis = \"Z\", a positive attribute, or standard_name height)"};
    for (int a = 0; a < 3; a++)
        if (l->axis_var[a] < 0) {
            if (!quiet)
                log_error("%s: no %s", path, what[a]);
            return false;
        }
    if (degrees[0] != degrees[1]) {
        if (!quiet)
            log_error("%s: x and y must both be in degrees (longitude, latitude) or both in "
                      "lengths",
                      path);
        return false;
    }
    l->latlon = degrees[0];
    if (l->time_dim < 0) { /* no time coordinate: the record dimension counts the steps */
        int unlim;
        if (nc_inq_unlimdim(ncid, &unlim) == NC_NOERR && unlim >= 0)
            l->time_dim = unlim;
    }
    char positive[16], units[64], bounds[NC_MAX_NAME + 1];
    if (text_att(ncid, l->axis_var[2], "positive", positive, sizeof(positive))) {
        if (!strcmp(positive, "down")) {
            l->z_sign = -1.0;
        } else if (strcmp(positive, "up") != 0) {
            if (!quiet)
                log_error("%s: vertical coordinate: positive = \"%s\": expected \"up\" or "
                          "\"down\"",
                          path, positive);
            return false;
        }
    }
    text_att(ncid, l->axis_var[2], "units", units, sizeof(units));
    double scale;
    if (!hgrid_parse_length(units, &scale)) {
        if (!quiet) {
            char name[NC_MAX_NAME + 1] = "?";
            nc_inq_varname(ncid, l->axis_var[2], name);
            log_error("%s: vertical coordinate %s: units \"%s\": expected a height (m or km); "
                      "pressure or model levels are not height levels",
                      path, name, units);
        }
        return false;
    }
    int b;
    if (text_att(ncid, l->axis_var[2], "bounds", bounds, sizeof(bounds)) &&
        nc_inq_varid(ncid, bounds, &b) == NC_NOERR) {
        int nd, dims[NC_MAX_VAR_DIMS];
        size_t two = 0;
        nc_inq_var(ncid, b, NULL, NULL, &nd, dims, NULL);
        if (nd == 2 && dims[0] == l->axis_dim[2])
            nc_inq_dimlen(ncid, dims[1], &two);
        if (two == 2)
            l->bounds_var[2] = b;
    }
    return true;
}

static bool identify(int ncid, const char *path, struct hgrid_layout *l)
{
    if (!find_axes(ncid, path, l, false))
        return false;
    int nvars;
    nc_inq_nvars(ncid, &nvars);
    int found = 0;
    for (int id = 0; id < nvars; id++) {
        char sn[128];
        if (!text_att(ncid, id, "standard_name", sn, sizeof(sn)))
            continue;
        for (int v = 0; v < HGRID_VAR_COUNT; v++) {
            if (strcmp(sn, standard[v]) != 0)
                continue;
            if (l->field[v].varid >= 0) {
                char name[NC_MAX_NAME + 1] = "?";
                nc_inq_varname(ncid, id, name);
                log_warn("%s: variable %s: a second %s (%s is read)", path, name, sn,
                         l->field[v].name);
                break;
            }
            /* A field on other dimensions (a 2 m temperature, a column total) is not one of
             * the levels': passed over. */
            int nd, dims[NC_MAX_VAR_DIMS];
            nc_inq_varndims(ncid, id, &nd);
            nc_inq_vardimid(ncid, id, dims);
            if (nd < 3 || nd > 4 || dims[nd - 3] != l->axis_dim[2] ||
                dims[nd - 2] != l->axis_dim[1] || dims[nd - 1] != l->axis_dim[0]) {
                char name[NC_MAX_NAME + 1] = "?";
                nc_inq_varname(ncid, id, name);
                log_debug("%s: variable %s (%s) is not on the height levels: not read", path,
                          name, sn);
                break;
            }
            if (!hgrid_take_field(ncid, path, id, (enum hgrid_var)v, -1, v <= HGRID_VAPOR, l))
                return false;
            found++;
            break;
        }
    }
    if (!found) {
        log_error("%s: no variable with a standard_name this reader knows (%s, %s, ...)", path,
                  standard[0], standard[HGRID_TEMPERATURE]);
        return false;
    }
    return true;
}

bool cf_probe(const char *path)
{
    int nc;
    char why[512];
    data_nc_lock_file(path, "reading", false);
    bool yes = data_nc_open(path, &nc, NULL, why, sizeof(why));
    if (yes) {
        struct hgrid_layout l;
        memset(&l, 0, sizeof(l));
        for (int a = 0; a < 3; a++)
            l.axis_var[a] = l.axis_dim[a] = l.stag_dim[a] = l.face_var[a] = l.bounds_var[a] = -1;
        l.time_var = l.time_dim = -1;
        l.z_sign = 1.0;
        yes = find_axes(nc, path, &l, true);
        bool field = false;
        int nvars = 0;
        nc_inq_nvars(nc, &nvars);
        for (int id = 0; id < nvars && yes && !field; id++) {
            char sn[128];
            if (!text_att(nc, id, "standard_name", sn, sizeof(sn)))
                continue;
            for (int v = 0; v < HGRID_VAR_COUNT && !field; v++)
                field = !strcmp(sn, standard[v]);
        }
        yes = yes && field;
        nc_close(nc);
    }
    data_nc_unlock();
    return yes;
}

struct hgrid *cf_open(const char *const *paths, int count, double memory_mb)
{
    return hgrid_open(HGRID_CF, identify, paths, count, memory_mb);
}
