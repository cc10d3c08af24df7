#include "data/detect.h"

#include <errno.h>
#include <fcntl.h>
#include <glob.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <netcdf.h>

#include "common/log.h"
#include "data/cf.h"
#include "data/cm1.h"
#include "data/extfile.h"
#include "data/isabel.h"
#include "data/nclock.h"
#include "data/ncopen.h"
#include "data/source.h"
#include "data/wrf.h"

/* The readers, each by its own probe, tried in order.  A new reader's probe goes here (a
 * NetCDF format with FOLDER false, a folder format with FOLDER true), with its kind in
 * detect.h and its words in EXPECTED below. */
struct reader_probe {
    enum data_kind kind;
    bool folder;
    bool (*probe)(const char *path);
};

static const struct reader_probe readers[] = {
    {DATA_KIND_WRF, false, wrf_probe},
    {DATA_KIND_CM1, false, cm1_probe},
    {DATA_KIND_CF, false, cf_probe}, /* the most general of the NetCDF readers: after them */
    {DATA_KIND_EXTINCTION, false, extfile_probe},
    {DATA_KIND_ISABEL, true, isabel_probe},
};

/* What the message of a file no reader takes says was expected. */
static const char expected_netcdf[] =
    "expected WRF output (the dimensions west_east, south_north, bottom_top and "
    "bottom_top_stag, the variables PH and PHB), CM1 output (xh, yh, zh and CM1's mass ratios "
    "qc, qr, ...), CF NetCDF on height levels (a vertical coordinate in metres and variables "
    "with CF standard_names of the hydrometeors) or an extinction file of anvil convert (the "
    "variable beta_ice)";
static const char expected_folder[] =
    "expected a folder of Isabel bricks (QCLOUDf01.bin, QRAINf01.bin, ...), of WRF output "
    "(wrfout_d01_...) or of NetCDF files (*.nc)";

const char *data_kind_name(enum data_kind k)
{
    switch (k) {
    case DATA_KIND_CONFIG:
        return "a scene config";
    case DATA_KIND_WRF:
        return "WRF output";
    case DATA_KIND_CM1:
        return "CM1 output";
    case DATA_KIND_CF:
        return "CF NetCDF on height levels";
    case DATA_KIND_EXTINCTION:
        return "an extinction file";
    case DATA_KIND_ISABEL:
        return "an Isabel folder";
    case DATA_KIND_UNKNOWN:
        return "unknown";
    case DATA_KIND_UNREADABLE:
        break;
    }
    return "unreadable";
}

bool data_kind_is_data(enum data_kind k)
{
    return k == DATA_KIND_WRF || k == DATA_KIND_CM1 || k == DATA_KIND_CF ||
           k == DATA_KIND_EXTINCTION || k == DATA_KIND_ISABEL;
}

bool data_kind_is_series(enum data_kind k)
{
    return k == DATA_KIND_WRF || k == DATA_KIND_CM1 || k == DATA_KIND_CF;
}

/* Appends up to MAX names of NetCDF dimensions (VARS false) or variables of NC to BUF. */
static void list_names(int nc, bool vars, int max, char *buf, size_t size)
{
    int n = 0;
    if ((vars ? nc_inq_nvars(nc, &n) : nc_inq_ndims(nc, &n)) != NC_NOERR)
        n = 0;
    size_t len = strlen(buf);
    if (n == 0)
        snprintf(buf + len, size - len, "none");
    for (int i = 0; i < n && i < max; i++) {
        char name[NC_MAX_NAME + 1] = "";
        if ((vars ? nc_inq_varname(nc, i, name) : nc_inq_dimname(nc, i, name)) != NC_NOERR)
            snprintf(name, sizeof(name), "?");
        len = strlen(buf);
        snprintf(buf + len, size - len, "%s%s", i ? ", " : "", name);
    }
    len = strlen(buf);
    if (n > max)
        snprintf(buf + len, size - len, " and %d more", n - max);
}

/* A NetCDF file no reader takes: what it holds. */
static void describe_netcdf(const char *path, char *why, size_t size)
{
    int nc;
    char found[1024] = "";
    data_nc_lock_file(path, "reading", false);
    if (data_nc_open(path, &nc, NULL, found, sizeof(found))) {
        snprintf(found, sizeof(found), "the dimensions ");
        list_names(nc, false, 8, found, sizeof(found));
        size_t len = strlen(found);
        snprintf(found + len, sizeof(found) - len, "; the variables ");
        list_names(nc, true, 10, found, sizeof(found));
        nc_close(nc);
    }
    data_nc_unlock();
    snprintf(why, size, "%s: a NetCDF file that no reader of anvil takes (it has %s): %s", path,
             found, expected_netcdf);
}

/* Whether the first bytes of the file at FD look like text: no NUL, few control bytes. */
static bool looks_like_text(const unsigned char *b, size_t n)
{
    size_t odd = 0;
    for (size_t i = 0; i < n; i++) {
        if (b[i] == 0)
            return false;
        if (b[i] < 0x20 && b[i] != '\n' && b[i] != '\r' && b[i] != '\t' && b[i] != '\f')
            odd++;
    }
    return odd * 100 <= n;
}

enum data_kind data_detect(const char *path, char *why, size_t why_size)
{
    why[0] = '\0';
    struct stat st;
    if (stat(path, &st) != 0) {
        snprintf(why, why_size, "%s: %s", path, strerror(errno));
        return DATA_KIND_UNREADABLE;
    }
    if (S_ISDIR(st.st_mode)) {
        for (size_t i = 0; i < sizeof(readers) / sizeof(readers[0]); i++) {
            if (readers[i].folder && readers[i].probe(path))
                return readers[i].kind;
        }
        snprintf(why, why_size, "%s: a folder that no reader of anvil takes: %s", path,
                 expected_folder);
        return DATA_KIND_UNKNOWN;
    }
    /* A FIFO or a device is refused without waiting on it. */
    char bad[512];
    int fd = file_open_regular(path, bad, sizeof(bad));
    if (fd < 0) {
        snprintf(why, why_size, "%s: %s: expected a scene config, a NetCDF file or an Isabel "
                 "folder", path, bad);
        return DATA_KIND_UNREADABLE;
    }
    unsigned char head[4096];
    ssize_t got = read(fd, head, sizeof(head));
    close(fd);
    if (got < 0) {
        snprintf(why, why_size, "%s: %s", path, strerror(errno));
        return DATA_KIND_UNREADABLE;
    }
    size_t n = (size_t)got;
    if (data_file_is_netcdf(path)) {
        /* A damaged header (a file cut short) is the reason, before any reader is asked. */
        int nc;
        data_nc_lock_file(path, "reading", false);
        bool ok = data_nc_open(path, &nc, NULL, bad, sizeof(bad));
        if (ok)
            nc_close(nc);
        data_nc_unlock();
        if (!ok) {
            snprintf(why, why_size, "%s: %s", path, bad);
            return DATA_KIND_UNREADABLE;
        }
        for (size_t i = 0; i < sizeof(readers) / sizeof(readers[0]); i++) {
            if (!readers[i].folder && readers[i].probe(path))
                return readers[i].kind;
        }
        describe_netcdf(path, why, why_size);
        return DATA_KIND_UNKNOWN;
    }
    if (n == 0) {
        /* Not taken for an empty config: a download that failed would show the built-in
         * storm. */
        snprintf(why, why_size, "%s: an empty file: expected a scene config, WRF output, an "
                 "extinction file or an Isabel folder", path);
        return DATA_KIND_UNKNOWN;
    }
    if ((uint64_t)st.st_size > FILE_TEXT_MAX) {
        snprintf(why, why_size, "%s: %llu bytes: larger than the %zu MiB a scene config may "
                 "have, and not NetCDF: expected a scene config, WRF output, an extinction "
                 "file or an Isabel folder", path, (unsigned long long)st.st_size,
                 FILE_TEXT_MAX >> 20);
        return DATA_KIND_UNKNOWN;
    }
    if (looks_like_text(head, n))
        return DATA_KIND_CONFIG;
    const char *hint = n >= 2 && head[0] == 0x1f && head[1] == 0x8b ? " (gzip-compressed: "
                                                                      "unpack it first)"
                       : n >= 4 && memcmp(head, "\x0eHDF", 4) == 0 ? " (HDF4: not NetCDF)"
                                                                   : "";
    snprintf(why, why_size,
             "%s: neither text (a scene config) nor NetCDF: it begins with the bytes "
             "%02x %02x %02x %02x%s: expected a scene config, WRF output, an extinction file "
             "or an Isabel folder",
             path, n > 0 ? head[0] : 0, n > 1 ? head[1] : 0, n > 2 ? head[2] : 0,
             n > 3 ? head[3] : 0, hint);
    return DATA_KIND_UNKNOWN;
}

/* DIR with the characters glob(3) reads as a pattern escaped, then SUFFIX, into OUT. */
static bool escaped_pattern(const char *dir, const char *suffix, char *out, size_t size)
{
    size_t n = 0, len = strlen(dir);
    while (len > 1 && dir[len - 1] == '/')
        len--; /* "run/" names the folder "run" */
    for (size_t i = 0; i < len; i++) {
        if (strchr("*?[\\", dir[i])) {
            if (n + 1 >= size)
                return false;
            out[n++] = '\\';
        }
        if (n + 1 >= size)
            return false;
        out[n++] = dir[i];
    }
    int w = snprintf(out + n, size - n, "%s%s", len == 1 && dir[0] == '/' ? "" : "/", suffix);
    return w >= 0 && (size_t)w < size - n;
}

bool data_folder_pattern(const char *dir, char *pattern, size_t size, size_t *count,
                         const char **what)
{
    /* WRF names its history files wrfout_d<domain>_<date> (every domain of a run with nests:
     * the pattern groups them by domain); anything else a folder holds is taken by its
     * extension, as a run folder also holds namelists, logs and boundary files. */
    static const struct {
        const char *suffix, *one, *many;
    } kinds[] = {{"wrfout_d*", "file of WRF output", "files of WRF output"},
                 {"*.nc", "NetCDF file", "NetCDF files"}};
    for (size_t i = 0; i < sizeof(kinds) / sizeof(kinds[0]); i++) {
        if (!escaped_pattern(dir, kinds[i].suffix, pattern, size))
            return false;
        glob_t g;
        int rc = glob(pattern, 0, NULL, &g);
        size_t files = 0;
        for (size_t m = 0; rc == 0 && m < g.gl_pathc; m++) {
            struct stat st;
            if (stat(g.gl_pathv[m], &st) == 0 && !S_ISDIR(st.st_mode))
                files++;
        }
        globfree(&g);
        if (files > 0) {
            *count = files;
            *what = files == 1 ? kinds[i].one : kinds[i].many;
            return true;
        }
    }
    pattern[0] = '\0';
    return false;
}
