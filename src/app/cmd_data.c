#include "app/cmd_data.h"

#include <glob.h>
#include <stdint.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "app/app.h"
#include "session/scene.h"
#include "session/stats.h"
#include "session/effects.h"
#include "common/log.h"
#include "common/progress.h"
#include <sys/stat.h>

#include "data/cf.h"
#include "data/cm1.h"
#include "data/extfile.h"
#include "data/geo.h"
#include "data/hgrid_write.h"
#include "data/isabel.h"
#include "data/nest.h"
#include "data/synth.h"
#include "data/wrf.h"
#include "data/wrf_write.h"
#include "render/image.h"
#include "render/video.h"

/* ---- anvil info ------------------------------------------------------------------------- */

static void print_range(const char *name, const struct wrf_var_stats *s)
{
    if (!s->read)
        return;
    printf("    %-7s %12.5g .. %-12.5g", name, s->min, s->max);
    size_t bad = wrf_var_stats_bad(s);
    if (bad)
        printf("  bad: %zu (NaN %zu, Inf %zu, fill %zu, negative %zu, >1 %zu)", bad, s->nan, s->inf,
               s->fill, s->negative, s->absurd);
    printf("\n");
}

static bool parse_triple_int(const char *s, int out[3]);
static bool parse_triple_double(const char *s, double out[3]);

/* What info may hold of one file (and one step): the default of data.memory. */
#define INFO_MEMORY_MB 4096.0

static int info_extinction(const char *path, double memory_mb)
{
    struct extfile *f = extfile_open(path, memory_mb);
    if (!f)
        return EXIT_BAD_INPUT;
    const struct grid3 *g = extfile_grid(f);
    printf("%s: extinction volumes (CF NetCDF)\n", path);
    printf("  grid        %d x %d x %d voxels of %.4g x %.4g x %.4g m\n", g->n[0], g->n[1], g->n[2],
           g->spacing[0], g->spacing[1], g->spacing[2]);
    printf("  extent      %.4g x %.4g x %.4g km from (%.4g, %.4g, %.4g) km\n",
           g->n[0] * g->spacing[0] / 1e3, g->n[1] * g->spacing[1] / 1e3,
           g->n[2] * g->spacing[2] / 1e3, g->origin[0] / 1e3, g->origin[1] / 1e3,
           g->origin[2] / 1e3);
    printf("  time steps  %d\n", extfile_step_count(f));
    int rc = EXIT_OK;
    for (int s = 0; s < extfile_step_count(f); s++) {
        struct ext_volume v;
        struct extfile_stats st;
        if (!extfile_read_step(f, s, &v, &st)) {
            rc = EXIT_BAD_INPUT;
            break;
        }
        double mi = 0, mw = 0;
        size_t n = grid3_count(g);
        for (size_t i = 0; i < n; i++) {
            mi = fmax(mi, v.beta[2 * i]);
            mw = fmax(mw, v.beta[2 * i + 1]);
        }
        printf("  %3d %-19s  max beta ice %.4g, water %.4g 1/m", s, extfile_step_date(f, s), mi,
               mw);
        size_t bad = st.nan + st.inf + st.fill + st.negative;
        if (bad)
            printf("  bad: %zu", bad);
        printf("\n");
        ext_volume_finish(&v);
    }
    extfile_close(f);
    return rc;
}

/* One domain's series; W stays the caller's. */
static int info_wrf_series(struct wrf *w, const char *const *paths, int count, double memory_mb)
{
    const struct wrf_meta *m = wrf_get_meta(w);
    for (int i = 0; i < count; i++)
        printf("%s%s", i ? ", " : "", paths[i]);
    printf(": WRF output\n");
    printf("  grid        %d x %d columns x %d mass levels (west_east x south_north x "
           "bottom_top), DX %.6g m, DY %.6g m\n",
           m->nx, m->ny, m->nz, m->dx, m->dy);
    printf("  projection  MAP_PROJ %d, CEN_LAT %.4f, CEN_LON %.4f, MP_PHYSICS %d\n", m->map_proj,
           m->cen_lat, m->cen_lon, m->mp_physics);
    if (isfinite(m->lat_min)) {
        char range[96];
        geo_format_range(range, sizeof(range), 3, m->lat_min, m->lat_max, m->lon_min, m->lon_max);
        printf("  lat/lon     %s%s\n", range, wrf_moves(w) ? " at the first step" : "");
        if (wrf_moves(w)) {
            int last = wrf_step_count(w) - 1;
            const struct wrf_meta *z = wrf_step_meta(w, last);
            if (z != m) {
                geo_format_range(range, sizeof(range), 3, z->lat_min, z->lat_max, z->lon_min,
                                 z->lon_max);
                printf("  moves       a moving nest: %s at the last step (%d); each step's map, "
                       "terrain and lat/lon are its own\n",
                       range, last);
            } else {
                printf("  moves       a moving nest: the first step's map, terrain and lat/lon "
                       "stand for every step (its steps' would not fit the budget)\n");
            }
        }
    }
    printf("  species     present:");
    for (int f = 0; f < SPECIES_COUNT; f++)
        if (m->has_species[f])
            printf(" %s", species_wrf_name((enum species)f));
    printf("%s; absent (read as zero):", m->has_qvapor ? " (and QVAPOR)" : "");
    int absent = 0;
    for (int f = 0; f < SPECIES_COUNT; f++)
        if (!m->has_species[f]) {
            printf(" %s", species_wrf_name((enum species)f));
            absent++;
        }
    printf("%s\n", absent ? "" : " none");
    printf("  terrain     HGT %s, LANDMASK %s\n", m->hgt ? "yes" : "no",
           m->landmask ? "yes" : "no");
    printf("  time steps  %d\n", wrf_step_count(w));

    struct wrf_desc d;
    wrf_desc_defaults(&d);
    d.qvapor = true;
    d.memory_mb = memory_mb;
    int rc = EXIT_OK;
    for (int s = 0; s < wrf_step_count(w); s++) {
        /* Every value checked, none resampled: the ranges and bad counts are the file's. */
        struct grid3 g;
        struct wrf_stats st;
        if (!wrf_scan_step(w, s, &d, &st) || !wrf_grid(w, &d, &g)) {
            rc = EXIT_BAD_INPUT;
            break;
        }
        if (s == 0)
            printf("  extent      %.4g x %.4g x %.4g km (uniform grid: %d levels of %.4g m, "
                   "top at the highest model top)\n",
                   g.n[0] * g.spacing[0] / 1e3, g.n[1] * g.spacing[1] / 1e3,
                   (g.origin[2] + g.n[2] * g.spacing[2]) / 1e3, g.n[2], g.spacing[2]);
        struct wrf_desc nd = d;
        nd.native_levels = true;
        struct grid3 ng;
        if (s == 0 && wrf_grid(w, &nd, &ng))
            printf("  own levels  %d, centres %.0f to %.0f m, the thinnest %.0f m (data.vertical = "
                   "\"native\", the default)\n",
                   ng.n[2], grid3_centre_z(&ng, 0), grid3_centre_z(&ng, ng.n[2] - 1),
                   grid3_min_dz(&ng));
        printf("  %3d %s  (%s)\n", s, wrf_step_date(w, s), wrf_step_path(w, s));
        for (int k = 0; k < WRF_VAR_COUNT; k++)
            print_range(wrf_var_name((enum wrf_var)k), &st.var[k]);
    }
    return rc;
}

/* A parent and its nests (data/nest.h): how they are placed, then each domain. */
static int info_nests(struct nest_set *n, double memory_mb)
{
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    struct nest_layout l;
    if (!nest_layout(n, &d, &l))
        return EXIT_BAD_INPUT;
    printf("%d WRF domains in one scene, composed on %d x %d columns of %.6g m (the outermost's "
           "extent at the finest spacing):\n",
           nest_domain_count(n), l.grid.n[0], l.grid.n[1], l.grid.spacing[0]);
    for (int i = 0; i < nest_domain_count(n); i++) {
        char line[1024];
        nest_describe(n, i, line, sizeof(line));
        printf("  %s\n", line);
    }
    int rc = EXIT_OK;
    for (int i = 0; i < nest_domain_count(n) && rc == EXIT_OK; i++) {
        const struct nest_domain *dom = nest_domain(n, i);
        printf("\n");
        rc = info_wrf_series(dom->wrf, &dom->path, 1, memory_mb);
    }
    return rc;
}

static int info_wrf(const char *const *paths, int count, double memory_mb)
{
    bool single;
    struct nest_set *n = nest_open(paths, count, memory_mb, &single);
    if (n) {
        int rc = info_nests(n, memory_mb);
        nest_close(n);
        return rc;
    }
    if (!single)
        return EXIT_BAD_INPUT;
    struct wrf *w = wrf_open(paths, count, memory_mb);
    if (!w)
        return EXIT_BAD_INPUT;
    int rc = info_wrf_series(w, paths, count, memory_mb);
    wrf_close(w);
    return rc;
}

static int info_hgrid(enum hgrid_kind kind, const char *const *paths, int count,
                      double memory_mb)
{
    struct hgrid *h = (kind == HGRID_CM1 ? cm1_open : cf_open)(paths, count, memory_mb);
    if (!h)
        return EXIT_BAD_INPUT;
    const struct hgrid_meta *m = hgrid_get_meta(h);
    for (int i = 0; i < count; i++)
        printf("%s%s", i ? ", " : "", paths[i]);
    printf(": %s\n", kind == HGRID_CM1 ? "CM1 output" : "CF NetCDF on height levels");
    printf("  grid        %d x %d columns x %d levels (%s x %s x %s), dx %.6g m, dy %.6g m\n",
           m->nx, m->ny, m->nz, m->axis_names[0], m->axis_names[1], m->axis_names[2], m->dx,
           m->dy);
    if (m->latlon) {
        char range[96];
        geo_format_range(range, sizeof(range), 3, m->lat0, m->lat0 + (m->ny - 1) * m->dlat, m->lon0,
                         m->lon0 + (m->nx - 1) * m->dlon);
        printf("  lat/lon     %s (regular)\n", range);
    } else
        printf("  origin      first column at x %.6g km, y %.6g km in the file (placed at the "
               "volume's west and south edge)\n",
               m->x0 / 1e3, m->y0 / 1e3);
    printf("  levels      %.6g to %.6g m (%s%s, %s), uniform grid: %d even levels of %.4g m\n",
           m->bottom_m, m->top_m, m->stretched ? "stretched" : "even",
           m->reversed ? ", stored top down" : "", m->z_units, m->nz,
           (m->top_m - m->bottom_m) / m->nz);
    struct grid3 ng;
    hgrid_grid(h, true, &ng);
    if (grid3_stretched(&ng))
        printf("  own levels  %d, centres %.0f to %.0f m, the thinnest %.0f m, kept as they are "
               "(data.vertical = \"native\", the default; \"uniform\" or data.levels: the even "
               "levels)\n",
               ng.n[2], grid3_centre_z(&ng, 0), grid3_centre_z(&ng, ng.n[2] - 1),
               grid3_min_dz(&ng));
    else if (m->stretched)
        printf("  own levels  not kept (more than %d, or a level on the lowest or highest face): "
               "the even levels\n",
               GRID3_LEVELS_MAX);
    printf("  variables  ");
    for (int v = 0; v < HGRID_VAR_COUNT; v++)
        if (m->field[v].varid >= 0)
            printf(" %s=%s", hgrid_var_label((enum hgrid_var)v), m->field[v].name);
    printf("\n  species     absent (read as zero):");
    int absent = 0;
    for (int f = 0; f < SPECIES_COUNT; f++)
        if (m->field[f].varid < 0) {
            printf(" %s", species_name((enum species)f));
            absent++;
        }
    printf("%s\n", absent ? "" : " none");
    printf("  time steps  %d\n", hgrid_step_count(h));
    struct hgrid_desc d = {.memory_mb = memory_mb, .qvapor = true, .temperature = true,
                           .wind = true};
    int rc = EXIT_OK;
    for (int s = 0; s < hgrid_step_count(h); s++) {
        struct field_volume v;
        struct hgrid_stats st;
        if (!hgrid_read_step(h, s, &d, &v, &st)) {
            rc = EXIT_BAD_INPUT;
            break;
        }
        if (s == 0)
            printf("  extent      %.4g x %.4g x %.4g km\n", v.grid.n[0] * v.grid.spacing[0] / 1e3,
                   v.grid.n[1] * v.grid.spacing[1] / 1e3,
                   (v.grid.origin[2] + v.grid.n[2] * v.grid.spacing[2]) / 1e3);
        printf("  %3d t = %.6g s %s (%s)\n", s, hgrid_step_seconds(h, s), hgrid_step_date(h, s),
               hgrid_step_path(h, s));
        for (int k = 0; k < HGRID_VAR_COUNT; k++)
            print_range(m->field[k].varid >= 0 ? m->field[k].name : "", &st.var[k]);
        field_volume_finish(&v);
    }
    hgrid_close(h);
    return rc;
}

static int info_isabel(const char *dir, const int size[3], const double extent_km[3])
{
    struct isabel_desc d = {.dir = dir};
    for (int a = 0; a < 3; a++) {
        d.n[a] = size[a];
        d.extent_m[a] = extent_km[a] * 1000.0;
    }
    int steps = isabel_step_count(&d);
    if (steps == 0)
        return EXIT_BAD_INPUT;
    int n[3] = {size[0] ? size[0] : 500, size[1] ? size[1] : 500, size[2] ? size[2] : 100};
    double e[3] = {extent_km[0] > 0 ? extent_km[0] : 2000.0,
                   extent_km[1] > 0 ? extent_km[1] : 2000.0,
                   extent_km[2] > 0 ? extent_km[2] : 19.8};
    struct grid3 g;
    isabel_grid(&d, &g);
    printf("%s: Isabel bricks (IEEE Visualization 2004 contest)\n", dir);
    printf("  grid        %d x %d x %d points (--isabel-size, data.isabel_size)\n", n[0], n[1],
           n[2]);
    printf("  extent      %.4g x %.4g x %.4g km (--isabel-extent, data.isabel_extent)\n", e[0],
           e[1], e[2]);
    printf("  heights     %.0f to %.0f m, every %.0f m (the levels; the lowest as published)\n",
           g.origin[2] + 0.5 * g.spacing[2], g.origin[2] + (g.n[2] - 0.5) * g.spacing[2],
           g.spacing[2]);
    printf("  lat/lon     %.1f to %.1f N, %.1f to %.1f E (the contest's published box)\n",
           ISABEL_LAT_SOUTH, ISABEL_LAT_NORTH, ISABEL_LON_WEST, ISABEL_LON_EAST);
    printf("  time steps  %d\n", steps);
    int rc = EXIT_OK;
    /* The ranges of the first step's bricks; later steps are only checked for which bricks
     * they have and their sizes (48 steps of 13 bricks are 62 GB to read). */
    {
        const int s = 0;
        printf("  %3d f%02d\n", s, s + 1);
        char absent[256] = "";
        for (int f = 0; f < ISABEL_FIELD_COUNT; f++) {
            struct isabel_brick_stats st;
            if (!isabel_brick_stats(&d, isabel_fields[f], s, &st)) {
                rc = EXIT_BAD_INPUT;
                break;
            }
            if (!st.present) {
                snprintf(absent + strlen(absent), sizeof(absent) - strlen(absent), " %s",
                         isabel_fields[f]);
                continue;
            }
            printf("    %-7s %12.5g .. %-12.5g", isabel_fields[f], st.min, st.max);
            if (st.land)
                printf("  land or bad: %zu", st.land);
            printf("\n");
        }
        if (absent[0])
            printf("    absent:%s\n", absent);
    }
    for (int s = 1; s < steps && rc == EXIT_OK; s++) {
        char present[256] = "";
        int count = 0;
        for (int f = 0; f < ISABEL_FIELD_COUNT; f++) {
            char path[4096];
            isabel_brick_path(&d, isabel_fields[f], s, path, sizeof(path));
            struct stat sb;
            if (stat(path, &sb) != 0)
                continue;
            if ((uint64_t)sb.st_size != (uint64_t)n[0] * n[1] * n[2] * 4) {
                log_error("%s: %lld bytes, expected %llu (%d x %d x %d big-endian floats: check "
                          "data.isabel_size)",
                          path, (long long)sb.st_size,
                          (unsigned long long)n[0] * n[1] * n[2] * 4, n[0], n[1], n[2]);
                rc = EXIT_BAD_INPUT;
                break;
            }
            snprintf(present + strlen(present), sizeof(present) - strlen(present), " %s",
                     isabel_fields[f]);
            count++;
        }
        if (rc == EXIT_OK && s == 1)
            printf("  later steps: the bricks each has (ranges: the first step's)\n");
        if (rc == EXIT_OK)
            printf("  %3d f%02d %s\n", s, s + 1,
                   count == ISABEL_FIELD_COUNT ? " all 13 bricks" : present);
    }
    return rc;
}

int cmd_info(int argc, char **argv)
{
    double memory_mb = INFO_MEMORY_MB;
    int first = 1, isabel_size[3] = {0, 0, 0};
    double isabel_extent[3] = {0, 0, 0};
    while (argc >= first + 2) {
        const char *o = argv[first], *v = argv[first + 1];
        if (!strcmp(o, "--memory")) {
            if (!app_option_double("info", "--memory", v, 1.0, 1048576.0, &memory_mb))
                return EXIT_BAD_INPUT;
        } else if (!strcmp(o, "--isabel-size")) {
            if (!parse_triple_int(v, isabel_size) || isabel_size[0] > 4096 ||
                isabel_size[1] > 4096 || isabel_size[2] > 4096) {
                log_error("info: --isabel-size %s: expected NXxNYxNZ, each 1 to 4096", v);
                return EXIT_BAD_INPUT;
            }
        } else if (!strcmp(o, "--isabel-extent")) {
            if (!parse_triple_double(v, isabel_extent)) {
                log_error("info: --isabel-extent %s: expected XxYxZ in km", v);
                return EXIT_BAD_INPUT;
            }
        } else {
            break;
        }
        first += 2;
    }
    if (argc <= first || !strcmp(argv[first], "--help") || !strcmp(argv[first], "-h")) {
        FILE *out = argc <= first ? stderr : stdout;
        fprintf(out, "usage: anvil info [--memory MIB] FILE...\n"
                     "       anvil info [--isabel-size NXxNYxNZ] [--isabel-extent XxYxZ] FOLDER\n"
                     "  Describes WRF output (one series: several files or a quoted pattern,\n"
                     "  ordered by Times), CM1 output, CF NetCDF on height levels (ordered by\n"
                     "  time), an extinction file or a folder of Isabel bricks, each known by its\n"
                     "  content: dimensions, species present and absent, time steps and dates,\n"
                     "  extent, lat/lon box, value ranges, bad-value counts.  --memory: what\n"
                     "  opening the files and reading one step may take (default 4096 MiB, as\n"
                     "  data.memory).  --isabel-size and --isabel-extent (km) as\n"
                     "  data.isabel_size and data.isabel_extent.\n");
        return argc <= first ? EXIT_USAGE : EXIT_OK;
    }
    struct app_inputs in;
    if (!app_inputs_collect("info", argv + first, argc - first, &in))
        return EXIT_BAD_INPUT;
    int rc;
    if (in.config) {
        log_error("info: %s is a text file (a scene config): info describes data files (WRF, "
                  "CM1 or CF output, an extinction file, an Isabel folder)",
                  in.config);
        rc = EXIT_BAD_INPUT;
    } else if (in.kind == DATA_KIND_EXTINCTION) {
        rc = info_extinction(in.files[0], memory_mb);
    } else if (in.kind == DATA_KIND_ISABEL) {
        rc = info_isabel(in.files[0], isabel_size, isabel_extent);
    } else if (in.kind == DATA_KIND_CM1 || in.kind == DATA_KIND_CF) {
        rc = info_hgrid(in.kind == DATA_KIND_CM1 ? HGRID_CM1 : HGRID_CF, in.files, in.count,
                        memory_mb);
    } else {
        rc = info_wrf(in.files, in.count, memory_mb);
    }
    app_inputs_finish(&in);
    return rc;
}

/* ---- anvil synth ------------------------------------------------------------------------ */

static bool parse_triple_int(const char *s, int out[3])
{
    char tail;
    return sscanf(s, "%dx%dx%d%c", &out[0], &out[1], &out[2], &tail) == 3 && out[0] > 0 &&
           out[1] > 0 && out[2] > 0;
}

static bool parse_triple_double(const char *s, double out[3])
{
    char tail;
    return sscanf(s, "%lfx%lfx%lf%c", &out[0], &out[1], &out[2], &tail) == 3 && out[0] > 0 &&
           out[1] > 0 && out[2] > 0;
}

static void synth_usage(FILE *out)
{
    fprintf(out, "usage: anvil synth -o OUT.nc [--format wrf|cm1|cf] [--size NXxNYxNZ]\n"
                 "                   [--steps N] [--extent XxYxZ] [--seed N]\n"
                 "                   [--start YYYY-MM-DD_hh:mm:ss] [--interval MIN]\n"
                 "                   [--center LAT,LON] [--stretch R]\n"
                 "                   [--nest NEST.nc [--nest-ratio R] [--nest-box I,J,NI,NJ]\n"
                 "                    [--nest-latlon]]\n"
                 "  Writes the procedural storm as WRF-convention NetCDF (or CM1's convention,\n"
                 "  or CF on height levels), evolving over the steps.  Defaults: --format wrf\n"
                 "  --size 128x128x64 --steps 1 --extent 60x60x16 (km) --seed 1\n"
                 "  --start 2000-01-01_00:00:00 --interval 10 --center 25,-89.\n"
                 "  --nest also writes a WRF nest (GRID_ID 2) of the same storm R times finer\n"
                 "  (default 3) over NI x NJ parent columns from column I, J (1-based; default\n"
                 "  the middle third), with PARENT_ID, I/J_PARENT_START and PARENT_GRID_RATIO\n"
                 "  (--nest-latlon: without them, placed by its XLAT/XLONG).\n"
                 "  --stretch R (cm1, cf): stretched levels over the same height, each R times\n"
                 "  as thick as the one below (default 1: even).\n");
}

/* Adds SECONDS to a WRF date (no time zones, proleptic Gregorian). */
static void date_add(const char *start, double seconds, char out[32])
{
    double t0;
    if (!extfile_parse_date(start, &t0))
        t0 = 0.0;
    long long t = (long long)llround(t0 + seconds);
    long long days = t / 86400, rem = t % 86400;
    if (rem < 0) {
        rem += 86400;
        days--;
    }
    /* civil_from_days */
    long long z = days + 719468;
    long long era = (z >= 0 ? z : z - 146096) / 146097;
    long long doe = z - era * 146097;
    long long yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
    long long y = yoe + era * 400;
    long long doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    long long mp = (5 * doy + 2) / 153;
    long long d = doy - (153 * mp + 2) / 5 + 1;
    long long m = mp + (mp < 10 ? 3 : -9);
    y += m <= 2;
    snprintf(out, 32, "%04d-%02d-%02d_%02d:%02d:%02d", (int)(y % 10000), (int)m % 100, (int)d % 100,
             (int)(rem / 3600) % 100, (int)(rem / 60 % 60), (int)(rem % 60));
}

/* The stretched levels of --stretch R over GRID's box: each level R times as thick as the one
 * below (a model's grid finer near the ground); false (logged) when they do not fit. */
static bool stretch_grid(const struct grid3 *grid, double r, struct grid3 *out)
{
    int n = grid->n[2];
    double h = n * grid->spacing[2], zc[GRID3_LEVELS_MAX];
    if (n > GRID3_LEVELS_MAX) {
        log_error("synth: --stretch: %d levels, at most %d on a stretched grid", n,
                  GRID3_LEVELS_MAX);
        return false;
    }
    double total = 0.0, below = 0.0, t = 1.0;
    for (int k = 0; k < n; k++, t *= r)
        total += t;
    t = 1.0;
    for (int k = 0; k < n; k++, t *= r) {
        zc[k] = grid->origin[2] + h * (below + 0.5 * t) / total;
        below += t;
    }
    if (h / total < DATA_SPACING_MIN_M) {
        log_error("synth: --stretch %g: the lowest level %g m thick, expected at least %g m", r,
                  h / total, DATA_SPACING_MIN_M);
        return false;
    }
    *out = *grid;
    return grid3_set_levels(out, zc, n, grid->origin[2], grid->origin[2] + h);
}

/* V's arrays from its (uniform) grid onto the stretched grid TO of the same box and columns:
 * each column linear in height between the uniform levels (the file then holds these). */
static bool stretch_fields(struct field_volume *v, const struct grid3 *to)
{
    const struct grid3 *g = &v->grid;
    size_t plane = (size_t)g->n[0] * g->n[1], cells = grid3_count(g);
    float **arrays[SPECIES_COUNT + 3];
    int count = 0;
    for (int f = 0; f < SPECIES_COUNT; f++)
        arrays[count++] = &v->q[f];
    arrays[count++] = &v->qvapor;
    arrays[count++] = &v->temperature;
    arrays[count++] = &v->rho_air;
    for (int a = 0; a < count; a++) {
        float *src = *arrays[a];
        if (!src)
            continue;
        float *dst = malloc(cells * sizeof(float));
        if (!dst) {
            log_error("synth: out of memory");
            return false;
        }
        for (int k = 0; k < g->n[2]; k++) {
            double u = grid3_z_to_voxel(g, grid3_centre_z(to, k)) - 0.5;
            int k0 = (int)floor(u);
            double w = u - k0;
            if (k0 < 0)
                k0 = 0, w = 0.0;
            if (k0 >= g->n[2] - 1)
                k0 = g->n[2] - 1, w = 0.0;
            int k1 = k0 + 1 < g->n[2] ? k0 + 1 : k0;
            for (size_t c = 0; c < plane; c++)
                dst[c + plane * k] = (float)((1.0 - w) * src[c + plane * k0] +
                                             w * src[c + plane * k1]);
        }
        free(src);
        *arrays[a] = dst;
    }
    v->grid = *to;
    return true;
}

/* The storm in CM1's or CF's convention (on stretched levels with STRETCH > 1). */
static int synth_hgrid(enum hgrid_kind kind, const char *out, struct synth_desc *sd, int steps,
                       const char *start, double interval_min, double lat, double lon,
                       double stretch)
{
    struct hgrid_write_desc wd = {.kind = kind, .start = start, .cen_lat = lat, .cen_lon = lon};
    struct hgrid_writer *w = NULL;
    for (int s = 0; s < steps; s++) {
        sd->time = steps > 1 ? (double)s / (steps - 1) : 0.0;
        struct field_volume fv;
        if (!synth_storm_fields(sd, &fv)) {
            hgrid_writer_destroy(w);
            return EXIT_BAD_INPUT;
        }
        struct grid3 sg;
        if (stretch > 1.0 && (!stretch_grid(&fv.grid, stretch, &sg) ||
                              !stretch_fields(&fv, &sg))) {
            field_volume_finish(&fv);
            hgrid_writer_destroy(w);
            return EXIT_BAD_INPUT;
        }
        if (!w)
            w = hgrid_writer_create(out, &fv.grid, &wd);
        bool ok = w && hgrid_writer_add(w, &fv, s * interval_min * 60.0);
        field_volume_finish(&fv);
        if (!ok) {
            hgrid_writer_destroy(w);
            return EXIT_FAILED;
        }
        log_info("synth: step %d/%d written", s + 1, steps);
    }
    if (!hgrid_writer_finish(w))
        return EXIT_FAILED;
    log_info("synth: %s: %d x %d x %d, %d steps (%s convention)", out, sd->n[0], sd->n[1],
             sd->n[2], steps, kind == HGRID_CM1 ? "CM1" : "CF");
    return EXIT_OK;
}

/* The storm as a parent (OUT) and its nest (NEST): made once at the nest's spacing over the
 * whole domain, the parent's columns cut from it (nest_cut), so both sample one field. */
static int synth_nest(const char *out, const char *nest, struct synth_desc *sd, int ratio,
                      const int box_in[4], bool latlon, int steps, const char *start,
                      double interval_min, double lat, double lon)
{
    int box[4] = {box_in[0], box_in[1], box_in[2], box_in[3]};
    if (box[2] == 0) { /* the middle third */
        for (int a = 0; a < 2; a++) {
            box[2 + a] = sd->n[a] / 3 > 2 ? sd->n[a] / 3 : 2;
            box[a] = 1 + (sd->n[a] - box[2 + a]) / 2;
        }
    }
    if (box[0] - 1 + box[2] > sd->n[0] || box[1] - 1 + box[3] > sd->n[1]) {
        log_error("synth: --nest-box %d,%d,%d,%d: beyond the parent's %d x %d columns", box[0],
                  box[1], box[2], box[3], sd->n[0], sd->n[1]);
        return EXIT_BAD_INPUT;
    }
    struct synth_desc fine = *sd;
    fine.n[0] *= ratio;
    fine.n[1] *= ratio;
    double dx = sd->extent_m[0] / sd->n[0], dy = sd->extent_m[1] / sd->n[1];
    struct wrf_write_desc pd = {.cen_lat = lat, .cen_lon = lon, .grid_id = 1, .parent_id = 1,
                                .i_parent_start = 1, .j_parent_start = 1,
                                .parent_grid_ratio = 1,
                                .map_corner_m = {-0.5 * sd->extent_m[0], -0.5 * sd->extent_m[1]}};
    struct wrf_write_desc nd = pd;
    nd.grid_id = 2;
    nd.i_parent_start = box[0];
    nd.j_parent_start = box[1];
    nd.parent_grid_ratio = ratio;
    nd.latlon_only = latlon;
    nd.map_corner_m[0] += (box[0] - 1) * dx;
    nd.map_corner_m[1] += (box[1] - 1) * dy;
    int fbox[4] = {(box[0] - 1) * ratio, (box[1] - 1) * ratio, box[2] * ratio, box[3] * ratio};
    struct wrf_writer *pw = NULL, *nw = NULL;
    int rc = EXIT_OK;
    for (int s = 0; s < steps && rc == EXIT_OK; s++) {
        fine.time = steps > 1 ? (double)s / (steps - 1) : 0.0;
        struct field_volume fv, pv, nv;
        if (!synth_storm_fields(&fine, &fv))
            return EXIT_BAD_INPUT;
        bool ok = nest_cut(&fv, ratio, NULL, &pv) && nest_cut(&fv, ratio, fbox, &nv);
        field_volume_finish(&fv);
        if (ok && !pw)
            pw = wrf_writer_create(out, &pv.grid, &pd);
        if (ok && !nw)
            nw = wrf_writer_create(nest, &nv.grid, &nd);
        char date[32];
        date_add(start, s * interval_min * 60.0, date);
        ok = ok && pw && nw && wrf_writer_add(pw, &pv, date) && wrf_writer_add(nw, &nv, date);
        field_volume_finish(&pv);
        field_volume_finish(&nv);
        if (!ok)
            rc = EXIT_FAILED;
        else
            log_info("synth: step %d/%d (%s) written", s + 1, steps, date);
    }
    if (rc != EXIT_OK) {
        wrf_writer_destroy(pw);
        wrf_writer_destroy(nw);
        return rc;
    }
    bool ok = wrf_writer_finish(pw);
    ok = wrf_writer_finish(nw) && ok;
    if (!ok)
        return EXIT_FAILED;
    log_info("synth: %s: %d x %d x %d; nest %s: %d x %d columns of %g m from column %d, %d", out,
             sd->n[0], sd->n[1], sd->n[2], nest, fbox[2], fbox[3], dx / ratio, box[0], box[1]);
    return EXIT_OK;
}

int cmd_synth(int argc, char **argv)
{
    const char *out = NULL, *start = "2000-01-01_00:00:00";
    int size[3] = {128, 128, 64}, steps = 1;
    double extent_km[3] = {60.0, 60.0, 16.0}, interval_min = 10.0, lat = 25.0, lon = -89.0;
    double stretch = 1.0;
    unsigned seed = 1;
    int format = 0; /* 0 WRF, 1 + enum hgrid_kind */
    const char *nest = NULL;
    int nest_ratio = 3, nest_box[4] = {0, 0, 0, 0};
    bool nest_latlon = false;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            synth_usage(stdout);
            return EXIT_OK;
        }
        if (!strcmp(a, "--nest-latlon")) {
            nest_latlon = true;
            continue;
        }
        if (!v) {
            log_error("synth: %s needs a value", a);
            synth_usage(stderr);
            return EXIT_USAGE;
        }
        i++;
        char tail;
        if (!strcmp(a, "-o") || !strcmp(a, "--output")) {
            out = v;
        } else if (!strcmp(a, "--format")) {
            if (!strcmp(v, "wrf"))
                format = 0;
            else if (!strcmp(v, "cm1"))
                format = 1 + HGRID_CM1;
            else if (!strcmp(v, "cf"))
                format = 1 + HGRID_CF;
            else {
                log_error("synth: --format %s: expected wrf, cm1 or cf", v);
                return EXIT_BAD_INPUT;
            }
        } else if (!strcmp(a, "--size")) {
            if (!parse_triple_int(v, size)) {
                log_error("synth: --size %s: expected NXxNYxNZ, e.g. 500x500x100", v);
                return EXIT_BAD_INPUT;
            }
        } else if (!strcmp(a, "--extent")) {
            if (!parse_triple_double(v, extent_km)) {
                log_error("synth: --extent %s: expected XxYxZ in km, e.g. 60x60x16", v);
                return EXIT_BAD_INPUT;
            }
        } else if (!strcmp(a, "--steps")) {
            if (sscanf(v, "%d%c", &steps, &tail) != 1 || steps < 1 || steps > 10000) {
                log_error("synth: --steps %s: expected a count from 1 to 10000", v);
                return EXIT_BAD_INPUT;
            }
        } else if (!strcmp(a, "--seed")) {
            if (sscanf(v, "%u%c", &seed, &tail) != 1) {
                log_error("synth: --seed %s: expected a non-negative integer", v);
                return EXIT_BAD_INPUT;
            }
        } else if (!strcmp(a, "--start")) {
            double t;
            if (!extfile_parse_date(v, &t)) {
                log_error("synth: --start %s: expected YYYY-MM-DD_hh:mm:ss", v);
                return EXIT_BAD_INPUT;
            }
            start = v;
        } else if (!strcmp(a, "--interval")) {
            if (sscanf(v, "%lf%c", &interval_min, &tail) != 1 || !(interval_min > 0)) {
                log_error("synth: --interval %s: expected minutes > 0", v);
                return EXIT_BAD_INPUT;
            }
        } else if (!strcmp(a, "--stretch")) {
            if (sscanf(v, "%lf%c", &stretch, &tail) != 1 || !(stretch >= 1.0 && stretch <= 2.0)) {
                log_error("synth: --stretch %s: expected a ratio from 1 to 2 (each level that "
                          "many times as thick as the one below)",
                          v);
                return EXIT_BAD_INPUT;
            }
        } else if (!strcmp(a, "--nest")) {
            nest = v;
        } else if (!strcmp(a, "--nest-ratio")) {
            if (sscanf(v, "%d%c", &nest_ratio, &tail) != 1 || nest_ratio < 2 || nest_ratio > 7) {
                log_error("synth: --nest-ratio %s: expected a whole ratio from 2 to 7", v);
                return EXIT_BAD_INPUT;
            }
        } else if (!strcmp(a, "--nest-box")) {
            if (sscanf(v, "%d,%d,%d,%d%c", &nest_box[0], &nest_box[1], &nest_box[2],
                       &nest_box[3], &tail) != 4 || nest_box[0] < 1 || nest_box[1] < 1 ||
                nest_box[2] < 2 || nest_box[3] < 2) {
                log_error("synth: --nest-box %s: expected I,J,NI,NJ: the first parent column "
                          "(from 1) and at least 2 x 2 columns",
                          v);
                return EXIT_BAD_INPUT;
            }
        } else if (!strcmp(a, "--center")) {
            if (sscanf(v, "%lf,%lf%c", &lat, &lon, &tail) != 2 || fabs(lat) > 80 ||
                fabs(lon) > 360) {
                log_error("synth: --center %s: expected LAT,LON in degrees (|LAT| <= 80)", v);
                return EXIT_BAD_INPUT;
            }
        } else {
            log_error("synth: unknown option %s", a);
            synth_usage(stderr);
            return EXIT_USAGE;
        }
    }
    if (!out) {
        log_error("synth: no output file (-o OUT.nc)");
        synth_usage(stderr);
        return EXIT_USAGE;
    }
    if (image_path_supported(out) || video_path_supported(out)) {
        log_error("%s: synth writes NetCDF, not a picture or a movie: expected a name like "
                  "storm.nc or wrfout_d01_2005-08-28_12:00:00",
                  out);
        return EXIT_BAD_INPUT;
    }
    struct synth_desc sd = {.kind = SYNTH_STORM, .seed = seed};
    for (int a = 0; a < 3; a++) {
        sd.n[a] = size[a];
        sd.extent_m[a] = extent_km[a] * 1000.0;
        double spacing = sd.extent_m[a] / size[a];
        /* What the readers take (data/volume.h): a file they would refuse is not written. */
        if (spacing < DATA_SPACING_MIN_M || spacing > DATA_SPACING_MAX_M ||
            (a == 2 && sd.extent_m[a] > DATA_HEIGHT_MAX_M)) {
            log_error("synth: --size %dx%dx%d --extent %gx%gx%g: cells of %g m along %c; "
                      "expected %g m to %g km, and at most %g km high",
                      size[0], size[1], size[2], extent_km[0], extent_km[1], extent_km[2], spacing,
                      "xyz"[a], DATA_SPACING_MIN_M, DATA_SPACING_MAX_M / 1000.0,
                      DATA_HEIGHT_MAX_M / 1000.0);
            return EXIT_BAD_INPUT;
        }
    }
    if (format && nest) {
        log_error("synth: --nest writes WRF nests: not with --format %s",
                  format == 1 + HGRID_CM1 ? "cm1" : "cf");
        return EXIT_USAGE;
    }
    if (stretch > 1.0 && !format) {
        log_error("synth: --stretch is for --format cm1 or cf (WRF files have their own eta "
                  "levels)");
        return EXIT_USAGE;
    }
    if (format)
        return synth_hgrid((enum hgrid_kind)(format - 1), out, &sd, steps, start, interval_min,
                           lat, lon, stretch);
    if (nest)
        return synth_nest(out, nest, &sd, nest_ratio, nest_box, nest_latlon, steps, start,
                          interval_min, lat, lon);
    struct wrf_write_desc wd = {.cen_lat = lat, .cen_lon = lon};
    struct wrf_writer *w = NULL;
    double t0 = time_now_ms();
    struct progress pr;
    progress_begin(&pr, "synth", "step", (uint64_t)steps);
    for (int s = 0; s < steps; s++) {
        progress_update(&pr, (uint64_t)s);
        sd.time = steps > 1 ? (double)s / (steps - 1) : 0.0;
        struct field_volume fv;
        if (!synth_storm_fields(&sd, &fv)) {
            wrf_writer_destroy(w);
            return EXIT_BAD_INPUT;
        }
        if (!w)
            w = wrf_writer_create(out, &fv.grid, &wd);
        char date[32];
        date_add(start, s * interval_min * 60.0, date);
        bool ok = w && wrf_writer_add(w, &fv, date);
        field_volume_finish(&fv);
        if (!ok) {
            wrf_writer_destroy(w);
            return EXIT_FAILED;
        }
        log_info("synth: step %d/%d (%s) written", s + 1, steps, date);
        progress_update(&pr, (uint64_t)s + 1);
    }
    progress_end(&pr);
    if (!wrf_writer_finish(w))
        return EXIT_FAILED;
    log_info("synth: %s: %d x %d x %d, %d steps in %.1f s", out, size[0], size[1], size[2], steps,
             (time_now_ms() - t0) / 1000.0);
    return EXIT_OK;
}

/* ---- anvil convert ---------------------------------------------------------------------- */

static void convert_usage(FILE *out)
{
    fprintf(out, "usage: anvil convert [CONFIG] [FILE...] -o OUT.nc [--set PATH=VALUE]...\n"
                 "  Precomputes per time step the ice-phase (ice + snow + graupel) and the\n"
                 "  water-phase (cloud + rain) extinction into a CF NetCDF file that the\n"
                 "  renderer loads with data.format = \"extinction\".  FILE...: WRF output or an\n"
                 "  Isabel folder (or quoted patterns), known by content; a config first (or\n"
                 "  alone) gives its data.* settings, optics and species toggles.\n");
}

int cmd_convert(int argc, char **argv)
{
    const char *out = NULL;
    char *inputs[CONFIG_MAX_FILES];
    int n_inputs = 0;
    char *sets[64];
    int n_sets = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            convert_usage(stdout);
            return EXIT_OK;
        } else if (!strcmp(a, "-o") || !strcmp(a, "--output") || !strcmp(a, "--set")) {
            if (i + 1 >= argc) {
                log_error("convert: %s needs a value", a);
                return EXIT_USAGE;
            }
            if (a[1] == 'o' || a[2] == 'o')
                out = argv[++i];
            else if (n_sets < 64)
                sets[n_sets++] = argv[++i];
        } else if (a[0] == '-' && a[1]) {
            log_error("convert: unknown option %s", a);
            convert_usage(stderr);
            return EXIT_USAGE;
        } else if (n_inputs < CONFIG_MAX_FILES) {
            inputs[n_inputs++] = argv[i];
        } else {
            log_error("convert: more than %d inputs", CONFIG_MAX_FILES);
            return EXIT_USAGE;
        }
    }
    if (!out || n_inputs == 0) {
        log_error("convert: %s", !out ? "no output file (-o OUT.nc)" : "no input");
        convert_usage(stderr);
        return EXIT_USAGE;
    }

    struct config *cfg = malloc(sizeof(*cfg));
    if (!cfg) {
        log_error("convert: out of memory");
        return EXIT_FAILED;
    }
    /* A config, or data files known by their content (a config first for the rest). */
    const char *config_path = NULL;
    if (app_load_scene("convert", inputs, n_inputs, sets, n_sets, cfg, &config_path) !=
        EXIT_OK) {
        free(cfg);
        return EXIT_BAD_INPUT;
    }
    if (cfg->scene.kind != SCENE_DATA || cfg->data.file_count == 0) {
        log_error("%s: data.files: no input files to convert", inputs[0]);
        free(cfg);
        return EXIT_BAD_INPUT;
    }
    if (cfg->data.format == DATA_EXTINCTION) {
        log_error("convert: the input is already an extinction file (data.format)");
        free(cfg);
        return EXIT_BAD_INPUT;
    }
    const char *ptrs[CONFIG_MAX_FILES];
    struct data_source_desc sd;
    scene_source_desc(cfg, ptrs, &sd);
    sd.height_scale = 1.0; /* a file keeps physical heights; detail, like species, is baked */
    struct data_source *src = data_source_open(&sd);
    if (!src) {
        free(cfg);
        return EXIT_BAD_INPUT;
    }

    /* Provenance: sources, command line, species settings (what the file can no longer
     * change). */
    char source[4096] = "", history[4096] = "", species[512] = "";
    for (int i = 0; i < sd.file_count; i++)
        snprintf(source + strlen(source), sizeof(source) - strlen(source), "%s%s", i ? " " : "",
                 sd.files[i]);
    for (int i = 0; i < argc; i++)
        snprintf(history + strlen(history), sizeof(history) - strlen(history), "%s%s",
                 i ? " " : "anvil ", argv[i]);
    for (int f = 0; f < SPECIES_COUNT; f++)
        snprintf(species + strlen(species), sizeof(species) - strlen(species), "%s%s %s x%g",
                 f ? ", " : "", species_name((enum species)f), sd.select.enabled[f] ? "on" : "off",
                 sd.select.scale[f]);

    int rc = EXIT_OK;
    struct extfile_writer *w = NULL;
    int steps = data_source_step_count(src);
    struct progress pr;
    progress_begin(&pr, "convert", "step", (uint64_t)steps);
    for (int s = 0; s < steps; s++) {
        progress_update(&pr, (uint64_t)s);
        struct ext_volume v;
        double load_ms, convert_ms;
        if (!data_source_load(src, s, &v, &load_ms, &convert_ms)) {
            rc = EXIT_BAD_INPUT;
            break;
        }
        if (!w)
            w = extfile_writer_create(out, &v.grid, source, history, species);
        bool ok = w && extfile_writer_add(w, &v, data_source_step_date(src, s));
        log_info("convert: step %d/%d %s: read %.0f ms, converted %.0f ms, max beta %.3g 1/m",
                 s + 1, steps, data_source_step_date(src, s), load_ms, convert_ms,
                 ext_volume_max_beta(&v));
        ext_volume_finish(&v);
        if (!ok) {
            rc = EXIT_FAILED;
            break;
        }
        progress_update(&pr, (uint64_t)s + 1);
    }
    progress_end(&pr);
    if (rc == EXIT_OK) {
        if (!extfile_writer_finish(w))
            rc = EXIT_FAILED;
    } else {
        extfile_writer_destroy(w);
    }
    data_source_close(src);
    free(cfg);
    return rc;
}
