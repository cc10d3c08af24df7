/*
 * data/series: the time series cache.  Holds extinction volumes of time steps in an LRU cache
 * bounded by a memory budget, and a background thread that loads (and converts) the steps
 * around the one being shown, so that stepping forward or back through time finds the next
 * step already in memory and the render loop never waits on file I/O for a step that was
 * prefetched (Dye 2007, time series caching).
 *
 * It knows nothing of formats: steps come from a load callback (data_source_load fits).  The
 * callback runs on the background thread only, one call at a time, so it needs no locking of
 * its own against other loads of the series.  All series_* functions are to be called from
 * one thread (the render loop).  No GL: uploading is the caller's.
 */
#ifndef ANVIL_DATA_SERIES_H
#define ANVIL_DATA_SERIES_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "data/volume.h"

/* Loads STEP into OUT (initialised by the callback); adds the milliseconds spent reading and
 * converting to *LOAD_MS and *CONVERT_MS.  Returns false (logged) on failure. */
typedef bool (*series_load_fn)(void *user, int step, struct ext_volume *out, double *load_ms,
                               double *convert_ms);

/* Zero means default for every member but step_count and load. */
struct series_desc {
    int step_count;
    series_load_fn load;
    void *user;
    double memory_mb; /* budget for all cached volumes; 0 = 1024 MiB.  The step being shown is
                         kept even when it alone is larger. */
    int prefetch;     /* steps to prefetch ahead and behind the current one; 0 = 1, -1 = none */
    bool wrap;        /* playback loops: after the last step comes the first */
    double delay_ms;  /* test hook: each load first sleeps this long (an artificially slow
                         reader) */
};

struct series_stats {
    unsigned hits;        /* acquires that found the step loaded */
    unsigned misses;      /* acquires that did not */
    unsigned frame_waits; /* series_acquire calls that blocked until a load finished */
    unsigned stale;       /* series_try_acquire calls that returned NULL (step not ready) */
    unsigned loads, failures, evictions;
    unsigned adopted; /* volumes the caller made and handed over (series_adopt), not loaded */
    double load_ms, convert_ms; /* totals over all loads, on the background thread */
    double wait_ms;             /* total time series_acquire blocked */
    size_t cached_bytes;        /* now */
    int cached_steps;           /* now */
};

struct series;

/* Starts the background thread.  NULL (logged) on failure.  Free with series_destroy, which
 * waits for a load in progress to finish. */
struct series *series_create(const struct series_desc *d);
void series_destroy(struct series *s); /* NULL is fine */

/* The volume of STEP, loading it now (and waiting: a frame wait) when it is not in memory.
 * Makes STEP the current one and asks the background thread for its neighbours.  The pointer
 * stays valid until the next series_acquire / series_try_acquire that returns another step, or
 * series_destroy.  NULL when the load failed (the loader logged why). */
const struct ext_volume *series_acquire(struct series *s, int step);

/* Never blocks: the volume of STEP if it is in memory (then as series_acquire), else NULL
 * after asking the background thread for it; the previous volume stays valid. */
const struct ext_volume *series_try_acquire(struct series *s, int step);

/* Asks the background thread for STEP (and its neighbours) without making it current: the
 * current volume stays as it is (a cluster's rank loading the step the others wait for). */
void series_want(struct series *s, int step);

/* STEP's neighbours asked of the background thread, STEP itself not: the caller holds it (the
 * first step, made before the series; series_adopt hands it over). */
void series_prefetch_around(struct series *s, int step);

/* Takes *VOL, made by the caller the way desc.load makes STEP's volume (with the loader's
 * current inputs), as STEP's cached volume, so that it is not loaded a second time; STEP becomes
 * the current step and its neighbours are prefetched.  *VOL is zeroed either way; where STEP is
 * already cached or loading, or was made before a series_invalidate, it is freed instead.
 * GENERATION: series_generation() when VOL's making began. */
void series_adopt(struct series *s, int step, uint64_t generation, struct ext_volume *vol);

/* Bumped by every series_invalidate: a volume made under another generation is stale. */
uint64_t series_generation(struct series *s);

/* Drops every cached step and any load in progress (its result is thrown away), because
 * what the loader produces has changed (species, tints, transfer function); the current step
 * and its neighbours are loaded again in the background.  Pointers returned before are
 * invalid afterwards. */
void series_invalidate(struct series *s);

/* Whether STEP is in memory now. */
bool series_ready(struct series *s, int step);

void series_get_stats(struct series *s, struct series_stats *out);

#endif
