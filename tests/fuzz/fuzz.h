/*
 * Shared by the libFuzzer harnesses (docs/stability.md, "Fuzzing"): each reads its input the
 * way the program does, from a file, so the checks that happen before a library sees the
 * bytes (regular files, size caps, the NetCDF header check) are fuzzed too.
 */
#ifndef ANVIL_FUZZ_H
#define ANVIL_FUZZ_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "common/log.h"

/* DATA as the file NAME in this process's own temporary folder; the path (static storage). */
static inline const char *fuzz_file(const uint8_t *data, size_t size, const char *name)
{
    static char dir[256], path[512];
    if (!dir[0]) {
        const char *base = getenv("TMPDIR");
        snprintf(dir, sizeof(dir), "%s/anvil-fuzz-XXXXXX", base && *base ? base : "/tmp");
        if (!mkdtemp(dir))
            abort();
        log_set_level(LOG_NONE); /* the inputs are wrong on purpose */
    }
    snprintf(path, sizeof(path), "%s/%s", dir, name);
    FILE *f = fopen(path, "wb");
    if (!f || (size && fwrite(data, 1, size, f) != size))
        abort();
    fclose(f);
    return path;
}

/* Whether DATA starts as a classic NetCDF file does.  The NetCDF harnesses take only those:
 * netcdf-c's NetCDF-4 code and HDF5 crash on malformed HDF5 files, which the program reports
 * as the library's crash (common/fatal.h) but which would stop a fuzzer looking for ours. */
static inline int fuzz_is_classic(const uint8_t *data, size_t size)
{
    return size >= 4 && data[0] == 'C' && data[1] == 'D' && data[2] == 'F';
}

#endif
