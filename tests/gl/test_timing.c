/* GPU timing that never waits (gpu.h, "timers"): measurements are numbered as they end, their
 * times arrive later and land in the log they were made for, a collect that waits leaves none
 * in flight, a full queue gives way, and the light map and the renderer time exactly what they
 * build and draw.  llvmpipe's timestamps do not advance across compute work, so the query
 * path's times read about 0 here: what is checked is where every time goes. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#include "session/lightmaps.h"
#include "session/scene.h"
#include "session/stats.h"
#include "common/log.h"
#include "gpu/gpu.h"
#include "light/light_gpu.h"
#include "render/render.h"

static struct gpu_context *ctx;
static struct renderer *renderer;

/* Every kept time of T arrived and is finite and not negative; they sum to its total. */
static void assert_all_arrived(const struct gpu_timings *t)
{
    assert_int_equal(t->arrived, t->count);
    double sum = 0.0;
    for (unsigned i = 0; i < t->count && i < GPU_TIMINGS_KEPT; i++) {
        assert_true(t->known[i]);
        assert_true(isfinite(t->ms[i]) && t->ms[i] >= 0.0);
        sum += t->ms[i];
    }
    if (t->count <= GPU_TIMINGS_KEPT)
        assert_true(fabs(sum - t->total_ms) <= 1e-9 * (1.0 + sum));
    for (unsigned i = t->count; i < GPU_TIMINGS_KEPT; i++)
        assert_false(t->known[i]);
}

/* The query path: more measurements than the queue holds, into two logs, numbered in each log
 * in the order they ended; then everything arrives. */
static void test_queries_numbered_and_all_collected(void **state)
{
    struct gpu_timer_queue q;
    gpu_timer_queue_init(&q, GPU_TIMER_QUERIES);
    struct gpu_timings a = {0}, b = {0};
    const int n = GPU_TIMER_QUEUE_SIZE + 36;
    for (int i = 0; i < n; i++) {
        gpu_timer_queue_begin(&q);
        gpu_finish(); /* a little GPU-side work between the stamps */
        struct gpu_timings *log = i % 3 == 0 ? &b : &a;
        unsigned before = log->count;
        assert_int_equal(gpu_timer_queue_end(&q, log), before + 1);
        assert_true(q.pending <= GPU_TIMER_QUEUE_SIZE);
        /* What arrived plus what is in flight is everything measured. */
        assert_int_equal(a.arrived + b.arrived + (unsigned)q.pending, a.count + b.count);
    }
    assert_int_equal(a.count, n - (n + 2) / 3);
    assert_int_equal(b.count, (n + 2) / 3);
    /* More than a queue's worth ended: the oldest were waited for to make room. */
    assert_true(a.arrived + b.arrived >= (unsigned)(n - GPU_TIMER_QUEUE_SIZE));

    int left = gpu_timer_queue_collect(&q, false); /* never waits */
    assert_true(left >= 0 && left <= GPU_TIMER_QUEUE_SIZE);
    assert_int_equal(a.arrived + b.arrived + (unsigned)left, a.count + b.count);
    assert_int_equal(gpu_timer_queue_collect(&q, true), 0);
    assert_int_equal(q.pending, 0);
    assert_all_arrived(&a);
    assert_all_arrived(&b);

    /* An end without a begin measures nothing. */
    unsigned count = a.count;
    assert_int_equal(gpu_timer_queue_end(&q, &a), 0);
    assert_int_equal(a.count, count);

    /* CPU time added while the GPU time is in flight is kept beside it. */
    struct gpu_timings d = {0};
    gpu_timer_queue_begin(&q);
    unsigned number = gpu_timer_queue_end(&q, &d);
    gpu_timings_add(&d, number, 5.0);
    assert_int_equal(gpu_timer_queue_collect(&q, true), 0);
    assert_true(d.known[number - 1] && d.ms[number - 1] >= 5.0 && d.total_ms >= 5.0);
    assert_all_arrived(&d);

    /* Finishing drops what is in flight without writing its log. */
    struct gpu_timings c = {0};
    gpu_timer_queue_begin(&q);
    assert_int_equal(gpu_timer_queue_end(&q, &c), 1);
    unsigned arrived = c.arrived;
    gpu_timer_queue_finish(&q);
    assert_int_equal(c.arrived, arrived);
    assert_int_equal(c.count, 1);
}

/* The software-driver path: the time is known when the measurement ends. */
static void test_wall_clock_known_at_once(void **state)
{
    struct gpu_timer_queue q;
    gpu_timer_queue_init(&q, GPU_TIMER_WALL);
    struct gpu_timings t = {0};
    for (int i = 0; i < 3; i++) {
        gpu_timer_queue_begin(&q);
        assert_int_equal(gpu_timer_queue_end(&q, &t), i + 1);
        assert_int_equal(t.arrived, i + 1);
        assert_int_equal(q.pending, 0);
    }
    assert_int_equal(gpu_timer_queue_collect(&q, false), 0);
    assert_all_arrived(&t);
    gpu_timer_queue_finish(&q);
}

static void sun_at(struct config *cfg, double elevation)
{
    cfg->light.elevation_deg = elevation;
}

/* The session's bookkeeping: one time per build and per timed view, none for untimed ones, all
 * of them there after a collect that waits, in either storage mode. */
static void test_builds_and_views_each_timed_once(void **state)
{
    struct config cfg;
    struct ext_volume vol = {0};
    const char *sets[] = {"scene.size=[24,24,12]", "render.width=32", "render.height=24",
                          "lightmap.resolution=[16,16,16]", "lightmap.mode=dense"};
    test_config_from(&cfg, sets, 5);
    test_upload_scene(renderer, &cfg, &vol);
    ext_volume_finish(&vol);
    struct render_settings rs;
    scene_render_settings(&cfg, &rs);
    struct render_view view;
    scene_camera_view(&cfg, cfg.render.width, cfg.render.height, &view);
    struct gpu_texture out = {0};

    struct lightmaps al;
    struct session_stats st = {0};
    assert_true(lightmaps_init(&al, &cfg));
    /* Untimed: the build is counted, no time is measured or logged. */
    assert_true(lightmaps_update(&al, &cfg, renderer, &st));
    assert_int_equal(st.light_builds, 1);
    double ms = -1.0;
    assert_false(light_gpu_last_build_ms(al.gpu, &ms));
    assert_true(ms == -1.0);
    assert_int_equal(lightmaps_collect_timings(&al, true), 0);
    assert_int_equal(st.build_times.count, 0);

    lightmaps_set_timing(&al, &st.build_times);
    renderer_set_timing(renderer, &st.view_times);
    const double suns[] = {20.0, 35.0, 50.0};
    for (int i = 0; i < 3; i++) {
        sun_at(&cfg, suns[i]);
        scene_render_settings(&cfg, &rs);
        for (int frame = 0; frame < 2; frame++) {
            lightmaps_collect_timings(&al, false);
            renderer_collect_timings(renderer, false);
            assert_true(lightmaps_update(&al, &cfg, renderer, &st)); /* builds once a sun */
            assert_true(renderer_draw(renderer, &rs, &view, &out));
        }
    }
    cfg.lightmap.mode = LIGHTMAP_COMPRESSED; /* adds the CPU compression to the build */
    assert_true(lightmaps_update(&al, &cfg, renderer, &st));
    assert_int_equal(st.light_builds, 5);
    assert_int_equal(st.build_times.count, 4);
    assert_int_equal(st.view_times.count, 6);

    assert_int_equal(lightmaps_collect_timings(&al, true), 0);
    assert_int_equal(renderer_collect_timings(renderer, true), 0);
    assert_all_arrived(&st.build_times);
    assert_all_arrived(&st.view_times);
    /* The last build's time, now known, is the log's last entry. */
    assert_true(light_gpu_last_build_ms(al.gpu, &ms));
    assert_true(fabs(ms - st.build_times.ms[3]) <= 1e-9 * (1.0 + ms));

    /* Timing off again: drawing adds no time. */
    renderer_set_timing(renderer, NULL);
    assert_true(renderer_draw(renderer, &rs, &view, &out));
    assert_int_equal(renderer_collect_timings(renderer, true), 0);
    assert_int_equal(st.view_times.count, 6);

    gpu_texture_finish(&out);
    lightmaps_finish(&al);
    renderer_set_light(renderer, NULL);
}

int main(void)
{
    log_set_level(LOG_WARN);
    ctx = test_gl_context_or_skip();
    renderer = renderer_create();
    if (!renderer)
        return 1;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_queries_numbered_and_all_collected),
        cmocka_unit_test(test_wall_clock_known_at_once),
        cmocka_unit_test(test_builds_and_views_each_timed_once),
    };
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    renderer_destroy(renderer);
    gpu_context_destroy(ctx);
    return rc;
}
