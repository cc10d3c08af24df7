#include "data/cm1.h"

#include <string.h>

#include <netcdf.h>

#include "common/log.h"
#include "data/nclock.h"
#include "data/ncopen.h"

/* CM1's names of the quantities, in enum hgrid_var order (temperature: none, CM1 writes th). */
static const char *const names[HGRID_VAR_COUNT] = {
    "qc", "qr", "qi", "qs", "qg", "qv", NULL, "th", "prs", "rho", "u", "v", "w",
};

static int var(int ncid, const char *name)
{
    int id;
    return nc_inq_varid(ncid, name, &id) == NC_NOERR ? id : -1;
}

/* The dimension of the 1-D coordinate NAME, -1 when there is none. */
static int coord_dim(int ncid, const char *name, int *varid)
{
    int id = var(ncid, name), nd, dim;
    if (varid)
        *varid = id;
    if (id < 0 || nc_inq_varndims(ncid, id, &nd) != NC_NOERR || nd != 1 ||
        nc_inq_vardimid(ncid, id, &dim) != NC_NOERR)
        return -1;
    return dim;
}

static bool identify(int ncid, const char *path, struct hgrid_layout *l)
{
    static const char *const axes[3] = {"xh", "yh", "zh"};
    static const char *const faces[3] = {"xf", "yf", "zf"};
    for (int a = 0; a < 3; a++) {
        l->axis_dim[a] = coord_dim(ncid, axes[a], &l->axis_var[a]);
        if (a == 2 && l->axis_dim[a] < 0)
            l->axis_dim[a] = coord_dim(ncid, "z", &l->axis_var[a]);
        if (l->axis_dim[a] < 0) {
            int nd = 0;
            if (a == 2 && var(ncid, "zh") >= 0)
                nc_inq_varndims(ncid, var(ncid, "zh"), &nd);
            if (nd > 1)
                log_error("%s: zh has %d dimensions: heights that follow the terrain are not "
                          "read (a 1-D height coordinate is needed)",
                          path, nd);
            else
                log_error("%s: not CM1 output: no coordinate %s%s (1-D)", path, axes[a],
                          a == 2 ? " or z" : "");
            return false;
        }
        l->stag_dim[a] = coord_dim(ncid, faces[a], NULL);
    }
    if (l->stag_dim[2] >= 0)
        l->face_var[2] = var(ncid, "zf");
    l->time_dim = coord_dim(ncid, "time", &l->time_var);
    if (l->time_dim < 0) { /* a time variable on an unlimited dimension of another name */
        int unlim;
        if (nc_inq_unlimdim(ncid, &unlim) == NC_NOERR && unlim >= 0)
            l->time_dim = unlim;
        if (l->time_var >= 0) {
            int nd, d;
            if (nc_inq_varndims(ncid, l->time_var, &nd) != NC_NOERR || nd != 1 ||
                nc_inq_vardimid(ncid, l->time_var, &d) != NC_NOERR || d != l->time_dim)
                l->time_var = -1;
        }
    }
    for (int v = 0; v < HGRID_VAR_COUNT; v++) {
        if (!names[v])
            continue;
        int id = var(ncid, names[v]);
        if (id < 0)
            continue;
        int stagger = v == HGRID_U ? 0 : v == HGRID_V ? 1 : v == HGRID_W ? 2 : -1;
        if (stagger >= 0 && l->stag_dim[stagger] < 0) {
            log_error("%s: variable %s: no coordinate %s for its staggered points", path,
                      names[v], faces[stagger]);
            return false;
        }
        if (!hgrid_take_field(ncid, path, id, (enum hgrid_var)v, stagger, true, l))
            return false;
    }
    return true;
}

bool cm1_probe(const char *path)
{
    int nc;
    char why[512];
    data_nc_lock_file(path, "reading", false);
    bool yes = data_nc_open(path, &nc, NULL, why, sizeof(why));
    if (yes) {
        yes = coord_dim(nc, "xh", NULL) >= 0 && coord_dim(nc, "yh", NULL) >= 0 &&
              (coord_dim(nc, "zh", NULL) >= 0 || coord_dim(nc, "z", NULL) >= 0);
        bool field = false;
        for (int v = 0; v < HGRID_VAR_COUNT && yes && !field; v++)
            field = names[v] && var(nc, names[v]) >= 0;
        yes = yes && field;
        nc_close(nc);
    }
    data_nc_unlock();
    return yes;
}

struct hgrid *cm1_open(const char *const *paths, int count, double memory_mb)
{
    return hgrid_open(HGRID_CM1, identify, paths, count, memory_mb);
}
