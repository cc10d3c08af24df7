#include "data/coast.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <netcdf.h>

#include "common/log.h"
#include "data/nclock.h"
#include "data/ncopen.h"

const char *coast_file(char resolution)
{
    static char path[1024];
    const char *dir = getenv("ANVIL_GSHHG_DIR");
    if (!dir || !*dir)
        dir = "/usr/share/gmt-gshhg";
    snprintf(path, sizeof(path), "%s/binned_GSHHS_%c.nc", dir, resolution);
    return path;
}

void coast_lines_finish(struct coast_lines *c)
{
    if (!c)
        return;
    free(c->first);
    free(c->count);
    free(c->level);
    free(c->lat);
    free(c->lon);
    memset(c, 0, sizeof(*c));
}

/* The arrays of a binned file, read whole (the low resolution is 96 280 points). */
struct binned {
    int bin_minutes, bins_x, bins_y, n_bins, n_segs, n_points;
    int *bin_first_seg;
    short *bin_n_segs;
    int *seg_info, *seg_first_point;
    short *dlon, *dlat;
};

static void binned_finish(struct binned *b)
{
    free(b->bin_first_seg);
    free(b->bin_n_segs);
    free(b->seg_info);
    free(b->seg_first_point);
    free(b->dlon);
    free(b->dlat);
}

static bool read_scalar(const char *path, int ncid, const char *name, int *v)
{
    int id;
    if (nc_inq_varid(ncid, name, &id) != NC_NOERR || nc_get_var_int(ncid, id, v) != NC_NOERR) {
        log_warn("%s: not a GSHHG binned shoreline file (no %s)", path, name);
        return false;
    }
    return true;
}

/* Reads variable NAME of N values (checked against its length) as int or short. */
static void *read_array(const char *path, int ncid, const char *name, size_t n, bool is_short)
{
    int id, ndims, dim;
    size_t len = 0;
    if (nc_inq_varid(ncid, name, &id) != NC_NOERR || nc_inq_varndims(ncid, id, &ndims) ||
        ndims != 1 || nc_inq_vardimid(ncid, id, &dim) || nc_inq_dimlen(ncid, dim, &len) ||
        len < n) {
        log_warn("%s: not a GSHHG binned shoreline file (%s missing or shorter than %zu)", path,
                  name, n);
        return NULL;
    }
    void *buf = malloc((n ? n : 1) * (is_short ? sizeof(short) : sizeof(int)));
    if (!buf) {
        log_error("%s: out of memory", path);
        return NULL;
    }
    int st = n == 0 ? NC_NOERR
             : is_short ? nc_get_var_short(ncid, id, buf)
                        : nc_get_var_int(ncid, id, buf);
    if (st != NC_NOERR) {
        log_warn("%s: %s: %s", path, name, nc_strerror(st));
        free(buf);
        return NULL;
    }
    return buf;
}

static bool binned_read(const char *path, struct binned *b)
{
    memset(b, 0, sizeof(*b));
    data_nc_lock_file(path, "reading", false);
    int ncid;
    char why[512];
    if (!data_nc_open(path, &ncid, NULL, why, sizeof(why))) {
        data_nc_unlock();
        log_warn("%s: cannot read the coastlines: %s (Debian package gmt-gshhg-low)", path, why);
        return false;
    }
    bool ok = read_scalar(path, ncid, "Bin_size_in_minutes", &b->bin_minutes) &&
              read_scalar(path, ncid, "N_bins_in_360_longitude_range", &b->bins_x) &&
              read_scalar(path, ncid, "N_bins_in_180_degree_latitude_range", &b->bins_y) &&
              read_scalar(path, ncid, "N_bins_in_file", &b->n_bins) &&
              read_scalar(path, ncid, "N_segments_in_file", &b->n_segs) &&
              read_scalar(path, ncid, "N_points_in_file", &b->n_points);
    /* Products in 64 bits: the file's ints may be anything. */
    if (ok && (b->bin_minutes <= 0 || b->bins_x <= 0 || b->bins_y <= 0 ||
               (int64_t)b->n_bins != (int64_t)b->bins_x * b->bins_y || b->n_segs < 0 ||
               b->n_points < 0 || (int64_t)b->bins_x * b->bin_minutes != 360 * 60 ||
               (int64_t)b->bins_y * b->bin_minutes != 180 * 60)) {
        log_warn("%s: inconsistent GSHHG bin layout (%d x %d bins of %d')", path, b->bins_x,
                  b->bins_y, b->bin_minutes);
        ok = false;
    }
    ok = ok &&
         (b->bin_first_seg = read_array(path, ncid, "Id_of_first_segment_in_a_bin", b->n_bins,
                                        false)) &&
         (b->bin_n_segs = read_array(path, ncid, "N_segments_in_a_bin", b->n_bins, true)) &&
         (b->seg_info = read_array(path, ncid, "Embedded_npts_levels_exit_entry_for_a_segment",
                                   b->n_segs, false)) &&
         (b->seg_first_point = read_array(path, ncid, "Id_of_first_point_in_a_segment",
                                          b->n_segs, false)) &&
         (b->dlon = read_array(path, ncid, "Relative_longitude_from_SW_corner_of_bin",
                               b->n_points, true)) &&
         (b->dlat = read_array(path, ncid, "Relative_latitude_from_SW_corner_of_bin",
                               b->n_points, true));
    nc_close(ncid);
    data_nc_unlock();
    if (!ok)
        binned_finish(b);
    return ok;
}

/* Appends a point; grows the arrays. */
struct builder {
    struct coast_lines *c;
    int cap_points, cap_lines;
    bool failed;
};

static void add_point(struct builder *bd, double lat, double lon)
{
    struct coast_lines *c = bd->c;
    if (c->n_points == bd->cap_points) {
        int cap = bd->cap_points ? 2 * bd->cap_points : 1024;
        double *a = realloc(c->lat, (size_t)cap * sizeof(double));
        if (a)
            c->lat = a;
        double *o = realloc(c->lon, (size_t)cap * sizeof(double));
        if (o)
            c->lon = o;
        if (!a || !o) {
            bd->failed = true;
            return;
        }
        bd->cap_points = cap;
    }
    c->lat[c->n_points] = lat;
    c->lon[c->n_points] = lon;
    c->n_points++;
    c->count[c->n_lines - 1]++;
}

static void begin_line(struct builder *bd, int level)
{
    struct coast_lines *c = bd->c;
    if (c->n_lines == bd->cap_lines) {
        int cap = bd->cap_lines ? 2 * bd->cap_lines : 256;
        int *f = realloc(c->first, (size_t)cap * sizeof(int));
        if (f)
            c->first = f;
        int *n = realloc(c->count, (size_t)cap * sizeof(int));
        if (n)
            c->count = n;
        int *l = realloc(c->level, (size_t)cap * sizeof(int));
        if (l)
            c->level = l;
        if (!f || !n || !l) {
            bd->failed = true;
            return;
        }
        bd->cap_lines = cap;
    }
    c->first[c->n_lines] = c->n_points;
    c->count[c->n_lines] = 0;
    c->level[c->n_lines] = level;
    c->n_lines++;
}

/* Ends the current line, dropping it when it has fewer than two points. */
static void end_line(struct builder *bd)
{
    struct coast_lines *c = bd->c;
    if (c->n_lines > 0 && c->count[c->n_lines - 1] < 2) {
        c->n_points -= c->count[c->n_lines - 1];
        c->n_lines--;
    }
}

static bool in_box(const double box[4], double lat, double lon)
{
    return lat >= box[0] && lat <= box[1] && lon >= box[2] && lon <= box[3];
}

bool coast_read(const char *path, const double box[4], int max_level, struct coast_lines *out)
{
    memset(out, 0, sizeof(*out));
    struct binned b;
    if (!binned_read(path, &b))
        return false;
    double centre = 0.5 * (box[2] + box[3]);
    double bin_deg = b.bin_minutes / 60.0, scale = bin_deg / 65535.0;
    struct builder bd = {.c = out};
    for (int bin = 0; bin < b.n_bins && !bd.failed; bin++) {
        /* Bins run west to east from longitude 0 and north to south from the pole. */
        double lon_sw = (bin % b.bins_x) * bin_deg;
        double lat_sw = 90.0 - (bin / b.bins_x + 1) * bin_deg;
        lon_sw += 360.0 * round((centre - (lon_sw + 0.5 * bin_deg)) / 360.0);
        if (lat_sw > box[1] || lat_sw + bin_deg < box[0] || lon_sw > box[3] ||
            lon_sw + bin_deg < box[2])
            continue;
        /* Segments s0 .. s0 + ns - 1 and points p0 .. p0 + npts - 1, compared so that no
         * sum can overflow. */
        int s0 = b.bin_first_seg[bin], ns = b.bin_n_segs[bin];
        if (s0 < 0 || ns < 0 || ns > b.n_segs - s0)
            continue;
        for (int s = s0; s < s0 + ns && !bd.failed; s++) {
            int info = b.seg_info[s];
            int npts = (int)((unsigned)info >> 9), level = (info >> 6) & 7;
            int p0 = b.seg_first_point[s];
            if (level > max_level || npts < 2 || p0 < 0 || npts > b.n_points - p0)
                continue;
            /* Runs of points inside the box, each with one neighbour outside kept. */
            bool open = false;
            for (int p = 0; p < npts && !bd.failed; p++) {
                double lon = lon_sw + (uint16_t)b.dlon[p0 + p] * scale;
                double lat = lat_sw + (uint16_t)b.dlat[p0 + p] * scale;
                bool inside = in_box(box, lat, lon);
                if (inside && !open) {
                    begin_line(&bd, level);
                    open = true;
                    if (p > 0 && !bd.failed)
                        add_point(&bd, lat_sw + (uint16_t)b.dlat[p0 + p - 1] * scale,
                                  lon_sw + (uint16_t)b.dlon[p0 + p - 1] * scale);
                }
                if (open && !bd.failed)
                    add_point(&bd, lat, lon);
                if (open && !inside) {
                    end_line(&bd);
                    open = false;
                }
            }
            if (open)
                end_line(&bd);
        }
    }
    binned_finish(&b);
    if (bd.failed) {
        log_error("%s: out of memory reading the coastlines", path);
        coast_lines_finish(out);
        return false;
    }
    return true;
}
