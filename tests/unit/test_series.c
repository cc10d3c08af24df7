/* Time series cache: prefetch hides a slow reader, LRU budget, failures, try_acquire. */
#include "testutil.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "common/log.h"
#include "data/series.h"
#include "data/source.h"
#include "data/synth.h"
#include "data/wrf_write.h"

#define NX 16
#define NY 16
#define NZ 8
#define VOLUME_BYTES (NX * NY * NZ * 2 * sizeof(float))

struct fake {
    atomic_int calls;
    int fail_step;
    atomic_int step_calls[64];
    char thread[32]; /* the loading thread's name, as `top -H` shows it (the last load's) */
};

/* Step S's volume holds S everywhere. */
static bool fake_load(void *user, int step, struct ext_volume *out, double *load_ms,
                      double *convert_ms)
{
    struct fake *f = user;
    atomic_fetch_add(&f->calls, 1);
    if (step >= 0 && step < 64)
        atomic_fetch_add(&f->step_calls[step], 1);
    FILE *comm = fopen("/proc/thread-self/comm", "r");
    if (comm) {
        if (!fgets(f->thread, sizeof(f->thread), comm))
            f->thread[0] = '\0';
        fclose(comm);
    }
    if (step == f->fail_step) {
        log_error("fake: step %d cannot be read", step);
        return false;
    }
    struct grid3 g = {.n = {NX, NY, NZ}, .spacing = {1, 1, 1}};
    if (!ext_volume_init(out, &g))
        return false;
    for (size_t i = 0; i < grid3_count(&g) * 2; i++)
        out->beta[i] = (float)step;
    *load_ms += 1.0;
    *convert_ms += 0.5;
    return true;
}

static void sleep_ms(int ms)
{
    struct timespec ts = {ms / 1000, (long)(ms % 1000) * 1000000L};
    nanosleep(&ts, NULL);
}

/* Renders "frames" of 5 ms until STEP is prefetched (at most 5 s). */
static void frames_until_ready(struct series *s, int step)
{
    for (int i = 0; i < 1000 && !series_ready(s, step); i++)
        sleep_ms(5);
    assert_true(series_ready(s, step));
}

static void test_prefetch_hides_slow_reader(void **state)
{
    struct fake f = {.fail_step = -1};
    struct series_desc d = {.step_count = 8, .load = fake_load, .user = &f, .delay_ms = 40};
    struct series *s = series_create(&d);
    assert_non_null(s);

    /* The first step cannot have been prefetched: one frame waits. */
    const struct ext_volume *v = series_acquire(s, 0);
    assert_non_null(v);
    assert_true(v->beta[0] == 0.0f);

    /* Stepping forward through prefetched steps: no frame waits, each is a hit. */
    for (int step = 1; step < 8; step++) {
        frames_until_ready(s, step);
        double t0 = time_now_ms();
        v = series_acquire(s, step);
        assert_true(time_now_ms() - t0 < 20.0); /* far less than the 40 ms reader */
        assert_non_null(v);
        assert_true(v->beta[123] == (float)step);
    }
    /* And back: the previous step was kept (or prefetched behind). */
    frames_until_ready(s, 6);
    v = series_acquire(s, 6);
    assert_true(v->beta[0] == 6.0f);

    struct series_stats st;
    series_get_stats(s, &st);
    assert_int_equal(st.frame_waits, 1);
    assert_int_equal(st.misses, 1);
    assert_int_equal(st.hits, 8);
    assert_true(st.loads >= 8);
    assert_true(st.load_ms >= 8 * 40.0); /* the artificial delay is part of the load time */
    assert_true(st.convert_ms >= 8 * 0.5);

    /* Jumping far without giving the prefetcher time does wait, and is counted. */
    frames_until_ready(s, 7);
    series_destroy(s);

    d.step_count = 40;
    s = series_create(&d);
    assert_non_null(series_acquire(s, 0));
    assert_non_null(series_acquire(s, 30));
    series_get_stats(s, &st);
    assert_int_equal(st.frame_waits, 2);
    series_destroy(s);
}

/* A volume of NX x NY x NZ holding VALUE everywhere. */
static void made_volume(struct ext_volume *v, float value)
{
    struct grid3 g = {.n = {NX, NY, NZ}, .spacing = {1, 1, 1}};
    assert_true(ext_volume_init(v, &g));
    for (size_t i = 0; i < grid3_count(&g) * 2; i++)
        v->beta[i] = value;
}

/* The first step, made by the caller before the series, is handed over rather than read again;
 * one made before a new look, or for a step already there, is dropped. */
static void test_adopt_first(void **state)
{
    struct fake f = {.fail_step = -1};
    struct series_desc d = {
        .step_count = 6, .load = fake_load, .user = &f, .prefetch = 2, .delay_ms = 10};
    struct series *s = series_create(&d);
    assert_non_null(s);
    uint64_t gen = series_generation(s);
    series_prefetch_around(s, 3);
    struct ext_volume first = {0};
    made_volume(&first, 99.0f);
    series_adopt(s, 3, gen, &first);
    assert_null(first.beta); /* the series holds it now */
    assert_true(series_ready(s, 3));
    for (int step = 1; step < 6; step++)
        frames_until_ready(s, step);
    const struct ext_volume *v = series_try_acquire(s, 3);
    assert_non_null(v);
    assert_true(v->beta[0] == 99.0f && v->beta[2 * NX * NY * NZ - 1] == 99.0f);
    sleep_ms(50); /* time for a stray load of step 3 to show */
    struct series_stats st;
    series_get_stats(s, &st);
    assert_int_equal(atomic_load(&f.step_calls[3]), 0);
    assert_int_equal(st.adopted, 1);
    assert_int_equal(st.loads, 4); /* steps 1, 2, 4, 5: the window of 2 around 3 */
    assert_int_equal(st.cached_steps, 5);
    assert_int_equal(st.frame_waits, 0);
    assert_string_equal(f.thread, "anvil-series\n"); /* named, so that a person can tell */

    /* Step 3 is there already: another volume for it is dropped, the cached one stays. */
    made_volume(&first, 7.0f);
    series_adopt(s, 3, series_generation(s), &first);
    assert_null(first.beta);
    v = series_try_acquire(s, 3);
    assert_true(v->beta[0] == 99.0f);

    /* A new look: a volume made under the old one is stale, and step 3 is read again. */
    series_invalidate(s);
    made_volume(&first, 7.0f);
    series_adopt(s, 3, gen, &first);
    assert_null(first.beta);
    frames_until_ready(s, 3);
    v = series_try_acquire(s, 3);
    assert_true(v->beta[0] == 3.0f);
    assert_true(atomic_load(&f.step_calls[3]) >= 1);
    series_get_stats(s, &st);
    assert_int_equal(st.adopted, 1);
    series_destroy(s);
}

struct waiter {
    struct series *s;
    int step;
    float value; /* the volume's, once acquired */
    double waited_ms;
};

static void *acquire_thread(void *arg)
{
    struct waiter *w = arg;
    double t0 = time_now_ms();
    const struct ext_volume *v = series_acquire(w->s, w->step);
    w->waited_ms = time_now_ms() - t0;
    w->value = v ? v->beta[0] : -1.0f;
    return NULL;
}

/* A series_acquire waiting for a step that is handed over meanwhile gets it then, not when the
 * worker's next load ends. */
static void test_adopt_wakes_a_waiter(void **state)
{
    struct fake f = {.fail_step = -1};
    struct series_desc d = {
        .step_count = 6, .load = fake_load, .user = &f, .prefetch = -1, .delay_ms = 1500};
    struct series *s = series_create(&d);
    assert_non_null(s);
    uint64_t gen = series_generation(s);
    series_want(s, 1); /* the worker is busy with step 1 for 1.5 s (its delay, then the load) */
    sleep_ms(200);     /* time for it to take step 1 before the waiter asks for step 3 */
    struct waiter w = {.s = s, .step = 3};
    pthread_t t;
    assert_int_equal(pthread_create(&t, NULL, acquire_thread, &w), 0);
    sleep_ms(100); /* the waiter is waiting for step 3 */
    struct ext_volume first = {0};
    made_volume(&first, 99.0f);
    series_adopt(s, 3, gen, &first);
    pthread_join(t, NULL);
    assert_true(w.value == 99.0f);
    assert_true(w.waited_ms < 900.0); /* not the 1.4 s left of step 1's load */
    assert_int_equal(atomic_load(&f.step_calls[3]), 0);
    series_destroy(s);
}

static void test_budget_and_lru(void **state)
{
    struct fake f = {.fail_step = -1};
    /* Room for three volumes. */
    struct series_desc d = {.step_count = 10,
                            .load = fake_load,
                            .user = &f,
                            .memory_mb = 3.5 * VOLUME_BYTES / 1048576.0};
    struct series *s = series_create(&d);
    for (int step = 0; step < 10; step++) {
        if (step)
            frames_until_ready(s, step);
        const struct ext_volume *v = series_acquire(s, step);
        assert_true(v->beta[0] == (float)step);
        struct series_stats st;
        series_get_stats(s, &st);
        assert_true(st.cached_bytes <= 3 * VOLUME_BYTES);
        assert_true(st.cached_steps <= 3);
    }
    struct series_stats st;
    series_get_stats(s, &st);
    assert_true(st.evictions >= 6);
    /* Step 0 was evicted long ago: asking for it again is a miss that waits. */
    assert_false(series_ready(s, 0));
    assert_non_null(series_acquire(s, 0));
    series_get_stats(s, &st);
    assert_int_equal(st.frame_waits, 2);
    series_destroy(s);

    /* A budget below one volume still shows the current step. */
    d.memory_mb = 0.5 * VOLUME_BYTES / 1048576.0;
    s = series_create(&d);
    const struct ext_volume *v = series_acquire(s, 4);
    assert_non_null(v);
    sleep_ms(20);
    assert_true(v->beta[0] == 4.0f); /* not freed by prefetches arriving meanwhile */
    series_destroy(s);
}

static void test_try_acquire_never_blocks(void **state)
{
    struct fake f = {.fail_step = -1};
    struct series_desc d = {
        .step_count = 4, .load = fake_load, .user = &f, .delay_ms = 50, .wrap = true};
    struct series *s = series_create(&d);
    double t0 = time_now_ms();
    assert_null(series_try_acquire(s, 2)); /* not there yet: asked for, no wait */
    assert_true(time_now_ms() - t0 < 20.0);
    frames_until_ready(s, 2);
    const struct ext_volume *v = series_try_acquire(s, 2);
    assert_non_null(v);
    assert_true(v->beta[0] == 2.0f);
    /* Wrapping: the neighbours of 3 are 0 and 2. */
    frames_until_ready(s, 3);
    assert_non_null(series_try_acquire(s, 3));
    frames_until_ready(s, 0);
    struct series_stats st;
    series_get_stats(s, &st);
    assert_int_equal(st.frame_waits, 0);
    assert_int_equal(st.stale, 1);
    series_destroy(s);
}

static void test_failed_load(void **state)
{
    struct fake f = {.fail_step = 2};
    struct series_desc d = {.step_count = 5, .load = fake_load, .user = &f};
    struct series *s = series_create(&d);
    unsigned errors = log_error_count();
    assert_non_null(series_acquire(s, 1));
    assert_null(series_acquire(s, 2)); /* prefetched or loaded now: either way it failed */
    assert_true(log_error_count() > errors);
    assert_non_null(series_acquire(s, 3));
    assert_null(series_acquire(s, 7)); /* out of range */
    struct series_stats st;
    series_get_stats(s, &st);
    assert_true(st.failures >= 1);
    series_destroy(s);
    series_destroy(NULL);
}

/* The real path: a synthetic WRF series through data_source and the cache. */
static bool source_load(void *user, int step, struct ext_volume *out, double *load_ms,
                        double *convert_ms)
{
    return data_source_load(user, step, out, load_ms, convert_ms);
}

static void test_wrf_series(void **state)
{
    char path[512];
    snprintf(path, sizeof(path), "%s", test_tmp_path("series.nc"));
    struct synth_desc sd = {
        .kind = SYNTH_STORM, .n = {24, 20, 12}, .extent_m = {30e3, 25e3, 12e3}, .seed = 3};
    struct wrf_writer *w = NULL;
    for (int step = 0; step < 3; step++) {
        struct field_volume fv;
        sd.time = step / 2.0;
        assert_true(synth_storm_fields(&sd, &fv));
        if (!w)
            w = wrf_writer_create(path, &fv.grid, NULL);
        char date[32];
        snprintf(date, sizeof(date), "2000-01-01_0%d:00:00", step);
        assert_true(wrf_writer_add(w, &fv, date));
        field_volume_finish(&fv);
    }
    assert_true(wrf_writer_finish(w));

    const char *files[1] = {path};
    struct data_source_desc dd = {.format = DATA_SOURCE_WRF, .files = files, .file_count = 1};
    wrf_desc_defaults(&dd.wrf);
    optics_params_defaults(&dd.optics);
    species_select_defaults(&dd.select);
    struct data_source *src = data_source_open(&dd);
    assert_non_null(src);
    assert_int_equal(data_source_step_count(src), 3);
    struct series_desc d = {.step_count = 3, .load = source_load, .user = src};
    struct series *s = series_create(&d);
    for (int step = 0; step < 3; step++) {
        if (step)
            frames_until_ready(s, step);
        const struct ext_volume *v = series_acquire(s, step);
        assert_non_null(v);
        assert_int_equal(v->grid.n[0], 24);
        assert_true(ext_volume_max_beta(v) > 0.0);
    }
    struct series_stats st;
    series_get_stats(s, &st);
    assert_int_equal(st.frame_waits, 1);
    assert_true(st.load_ms > 0.0 && st.convert_ms > 0.0);
    series_destroy(s);
    data_source_close(src);
}

int main(void)
{
    log_set_level(LOG_ERROR);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_prefetch_hides_slow_reader),
        cmocka_unit_test(test_budget_and_lru),
        cmocka_unit_test(test_adopt_first),
        cmocka_unit_test(test_adopt_wakes_a_waiter),
        cmocka_unit_test(test_try_acquire_never_blocks),
        cmocka_unit_test(test_failed_load),
        cmocka_unit_test(test_wrf_series),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
