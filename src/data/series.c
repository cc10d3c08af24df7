#include "data/series.h"

#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "common/log.h"
#include "common/parallel.h"

enum entry_state { ENTRY_EMPTY, ENTRY_LOADING, ENTRY_READY, ENTRY_FAILED };

struct entry {
    enum entry_state state;
    struct ext_volume vol;
    size_t bytes;
    uint64_t last_used;
};

#define WANTED_MAX 64

struct series {
    struct series_desc desc;
    size_t budget;
    struct entry *entries;
    int current; /* -1 before the first acquire */
    int demand;  /* the step series_acquire is waiting for, or -1 */
    uint64_t clock;
    uint64_t generation; /* bumped by series_invalidate: loads begun before are dropped */

    /* Steps the worker should load, most urgent first. */
    int wanted[WANTED_MAX];
    int n_wanted;

    pthread_t thread;
    pthread_mutex_t lock;
    pthread_cond_t work; /* worker: something to do or quit */
    pthread_cond_t done; /* render loop: a load finished */
    bool quit;
    struct series_stats stats;
};

static void sleep_ms(double ms)
{
    if (ms <= 0.0)
        return;
    struct timespec ts = {.tv_sec = (time_t)(ms / 1000.0),
                          .tv_nsec = (long)((ms - 1000.0 * (time_t)(ms / 1000.0)) * 1e6)};
    while (nanosleep(&ts, &ts) != 0) {
    }
}

static int wrap_step(const struct series *s, int step)
{
    int n = s->desc.step_count;
    if (s->desc.wrap)
        return ((step % n) + n) % n;
    return (step >= 0 && step < n) ? step : -1;
}

static bool in_window(const struct series *s, int step)
{
    for (int i = 0; i < s->n_wanted; i++)
        if (s->wanted[i] == step)
            return true;
    return false;
}

/* Frees least recently used volumes until the cache fits the budget.  Never the current step;
 * steps outside the prefetch window go first.  Called with the lock held. */
static void evict(struct series *s)
{
    while (s->stats.cached_bytes > s->budget) {
        int victim = -1;
        for (int pass = 0; pass < 2 && victim < 0; pass++) {
            for (int i = 0; i < s->desc.step_count; i++) {
                struct entry *e = &s->entries[i];
                if (e->state != ENTRY_READY || i == s->current || i == s->demand ||
                    (pass == 0 && in_window(s, i)))
                    continue;
                if (victim < 0 || e->last_used < s->entries[victim].last_used)
                    victim = i;
            }
        }
        if (victim < 0)
            return;
        /* A prefetched step that does not fit is not fetched again until the window moves
         * (else the worker would load and evict it forever). */
        for (int i = 0; i < s->n_wanted; i++) {
            if (s->wanted[i] == victim) {
                memmove(&s->wanted[i], &s->wanted[i + 1],
                        (size_t)(s->n_wanted - i - 1) * sizeof(int));
                s->n_wanted--;
                break;
            }
        }
        struct entry *e = &s->entries[victim];
        ext_volume_finish(&e->vol);
        s->stats.cached_bytes -= e->bytes;
        s->stats.cached_steps--;
        s->stats.evictions++;
        e->bytes = 0;
        e->state = ENTRY_EMPTY;
    }
}

/* E holds *VOL from now on (ready, most recently used).  Called with the lock held. */
static void keep(struct series *s, struct entry *e, struct ext_volume *vol)
{
    e->vol = *vol;
    memset(vol, 0, sizeof(*vol));
    e->bytes = grid3_count(&e->vol.grid) * (2 * sizeof(float) + (e->vol.tint ? 4 : 0));
    e->state = ENTRY_READY;
    e->last_used = ++s->clock;
    s->stats.cached_bytes += e->bytes;
    s->stats.cached_steps++;
}

static void *worker(void *arg)
{
    struct series *s = arg;
    parallel_name_thread("anvil-series");
    pthread_mutex_lock(&s->lock);
    for (;;) {
        int step = -1;
        while (!s->quit) {
            for (int i = 0; i < s->n_wanted && step < 0; i++) {
                if (s->entries[s->wanted[i]].state == ENTRY_EMPTY)
                    step = s->wanted[i];
            }
            if (step >= 0)
                break;
            pthread_cond_wait(&s->work, &s->lock);
        }
        if (s->quit)
            break;
        struct entry *e = &s->entries[step];
        e->state = ENTRY_LOADING;
        uint64_t generation = s->generation;
        pthread_mutex_unlock(&s->lock);

        double t0 = time_now_ms();
        sleep_ms(s->desc.delay_ms);
        double load_ms = time_now_ms() - t0, convert_ms = 0.0;
        struct ext_volume vol;
        memset(&vol, 0, sizeof(vol));
        bool ok = s->desc.load(s->desc.user, step, &vol, &load_ms, &convert_ms);

        pthread_mutex_lock(&s->lock);
        s->stats.loads++;
        s->stats.load_ms += load_ms;
        s->stats.convert_ms += convert_ms;
        if (generation != s->generation) {
            ext_volume_finish(&vol); /* invalidated while loading: load again */
            e->state = ENTRY_EMPTY;
        } else if (ok) {
            keep(s, e, &vol);
            evict(s);
        } else {
            ext_volume_finish(&vol);
            e->state = ENTRY_FAILED;
            s->stats.failures++;
        }
        pthread_cond_broadcast(&s->done);
    }
    pthread_mutex_unlock(&s->lock);
    return NULL;
}

struct series *series_create(const struct series_desc *d)
{
    if (d->step_count <= 0 || !d->load) {
        log_error("time series: nothing to load (%d steps)", d->step_count);
        return NULL;
    }
    struct series *s = calloc(1, sizeof(*s));
    if (!s) {
        log_error("time series: out of memory");
        return NULL;
    }
    s->desc = *d;
    if (s->desc.prefetch == 0)
        s->desc.prefetch = 1;
    if (s->desc.prefetch < 0)
        s->desc.prefetch = 0;
    if (s->desc.prefetch > WANTED_MAX / 2 - 1)
        s->desc.prefetch = WANTED_MAX / 2 - 1;
    s->budget = (size_t)((d->memory_mb > 0 ? d->memory_mb : 1024.0) * 1048576.0);
    s->current = -1;
    s->demand = -1;
    s->entries = calloc((size_t)d->step_count, sizeof(*s->entries));
    if (!s->entries) {
        log_error("time series: out of memory for %d steps", d->step_count);
        goto error_entries;
    }
    if (pthread_mutex_init(&s->lock, NULL) != 0)
        goto error_lock;
    if (pthread_cond_init(&s->work, NULL) != 0)
        goto error_work;
    if (pthread_cond_init(&s->done, NULL) != 0)
        goto error_done;
    if (pthread_create(&s->thread, NULL, worker, s) != 0) {
        log_error("time series: cannot start the prefetch thread");
        goto error_thread;
    }
    return s;

error_thread:
    pthread_cond_destroy(&s->done);
error_done:
    pthread_cond_destroy(&s->work);
error_work:
    pthread_mutex_destroy(&s->lock);
error_lock:
    free(s->entries);
error_entries:
    free(s);
    return NULL;
}

void series_destroy(struct series *s)
{
    if (!s)
        return;
    pthread_mutex_lock(&s->lock);
    s->quit = true;
    pthread_cond_broadcast(&s->work);
    pthread_mutex_unlock(&s->lock);
    pthread_join(s->thread, NULL);
    for (int i = 0; i < s->desc.step_count; i++)
        ext_volume_finish(&s->entries[i].vol);
    pthread_cond_destroy(&s->done);
    pthread_cond_destroy(&s->work);
    pthread_mutex_destroy(&s->lock);
    free(s->entries);
    free(s);
}

/* The worker's list: STEP itself (if wanted), then the neighbours, forward before backward,
 * nearest first.  Called with the lock held. */
static void set_window(struct series *s, int step, bool include_step)
{
    s->n_wanted = 0;
    if (include_step)
        s->wanted[s->n_wanted++] = step;
    for (int d = 1; d <= s->desc.prefetch; d++) {
        int cand[2] = {wrap_step(s, step + d), wrap_step(s, step - d)};
        for (int c = 0; c < 2; c++) {
            if (cand[c] >= 0 && cand[c] != step && !in_window(s, cand[c]) &&
                s->n_wanted < WANTED_MAX)
                s->wanted[s->n_wanted++] = cand[c];
        }
    }
    pthread_cond_signal(&s->work);
}

static bool valid_step(const struct series *s, int step)
{
    if (step >= 0 && step < s->desc.step_count)
        return true;
    log_error("time step %d out of range (0 to %d)", step, s->desc.step_count - 1);
    return false;
}

static const struct ext_volume *make_current(struct series *s, int step)
{
    struct entry *e = &s->entries[step];
    e->last_used = ++s->clock;
    s->current = step;
    evict(s);
    return &e->vol;
}

const struct ext_volume *series_acquire(struct series *s, int step)
{
    if (!valid_step(s, step))
        return NULL;
    pthread_mutex_lock(&s->lock);
    struct entry *e = &s->entries[step];
    const struct ext_volume *v = NULL;
    if (e->state == ENTRY_READY) {
        s->stats.hits++;
        set_window(s, step, false);
        v = make_current(s, step);
        pthread_mutex_unlock(&s->lock);
        return v;
    }
    s->stats.misses++;
    s->stats.frame_waits++;
    if (e->state == ENTRY_FAILED)
        e->state = ENTRY_EMPTY; /* asked for explicitly: try again */
    set_window(s, step, true);
    s->demand = step;
    double t0 = time_now_ms();
    while (e->state == ENTRY_EMPTY || e->state == ENTRY_LOADING)
        pthread_cond_wait(&s->done, &s->lock);
    s->demand = -1;
    s->stats.wait_ms += time_now_ms() - t0;
    if (e->state == ENTRY_READY)
        v = make_current(s, step);
    pthread_mutex_unlock(&s->lock);
    return v;
}

const struct ext_volume *series_try_acquire(struct series *s, int step)
{
    if (!valid_step(s, step))
        return NULL;
    pthread_mutex_lock(&s->lock);
    struct entry *e = &s->entries[step];
    const struct ext_volume *v = NULL;
    if (e->state == ENTRY_READY) {
        s->stats.hits++;
        set_window(s, step, false);
        v = make_current(s, step);
    } else {
        s->stats.stale++;
        if (e->state != ENTRY_FAILED)
            set_window(s, step, true);
    }
    pthread_mutex_unlock(&s->lock);
    return v;
}

void series_want(struct series *s, int step)
{
    if (!valid_step(s, step))
        return;
    pthread_mutex_lock(&s->lock);
    const struct entry *e = &s->entries[step];
    if (e->state != ENTRY_READY && e->state != ENTRY_FAILED)
        set_window(s, step, true);
    pthread_mutex_unlock(&s->lock);
}

void series_prefetch_around(struct series *s, int step)
{
    if (!valid_step(s, step))
        return;
    pthread_mutex_lock(&s->lock);
    set_window(s, step, false);
    pthread_mutex_unlock(&s->lock);
}

void series_adopt(struct series *s, int step, uint64_t generation, struct ext_volume *vol)
{
    if (!valid_step(s, step) || !vol->beta) {
        ext_volume_finish(vol);
        return;
    }
    pthread_mutex_lock(&s->lock);
    struct entry *e = &s->entries[step];
    if (e->state == ENTRY_EMPTY && generation == s->generation) {
        keep(s, e, vol);
        s->stats.adopted++;
        set_window(s, step, false);
        make_current(s, step);
        pthread_cond_broadcast(&s->done); /* a series_acquire of STEP waiting elsewhere */
    }
    pthread_mutex_unlock(&s->lock);
    ext_volume_finish(vol); /* zeroed when kept */
}

uint64_t series_generation(struct series *s)
{
    pthread_mutex_lock(&s->lock);
    uint64_t g = s->generation;
    pthread_mutex_unlock(&s->lock);
    return g;
}

void series_invalidate(struct series *s)
{
    pthread_mutex_lock(&s->lock);
    s->generation++;
    for (int i = 0; i < s->desc.step_count; i++) {
        struct entry *e = &s->entries[i];
        if (e->state == ENTRY_READY) {
            ext_volume_finish(&e->vol);
            s->stats.cached_bytes -= e->bytes;
            s->stats.cached_steps--;
            e->bytes = 0;
        }
        if (e->state != ENTRY_LOADING)
            e->state = ENTRY_EMPTY;
    }
    if (s->current >= 0)
        set_window(s, s->current, true);
    pthread_mutex_unlock(&s->lock);
}

bool series_ready(struct series *s, int step)
{
    if (step < 0 || step >= s->desc.step_count)
        return false;
    pthread_mutex_lock(&s->lock);
    bool ready = s->entries[step].state == ENTRY_READY;
    pthread_mutex_unlock(&s->lock);
    return ready;
}

void series_get_stats(struct series *s, struct series_stats *out)
{
    pthread_mutex_lock(&s->lock);
    *out = s->stats;
    pthread_mutex_unlock(&s->lock);
}
