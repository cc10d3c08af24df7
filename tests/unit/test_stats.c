/* The --stats report's times: a timing log keeps the first GPU_TIMINGS_KEPT times by number
 * and sums all of them; the report lists each kept time, null where one has not arrived. */
#include "testutil.h"

#include <stdlib.h>
#include <string.h>

#include "session/stats.h"
#include "common/log.h"
#include "gpu/gpu.h"

static void test_timings_add_by_number(void **state)
{
    struct gpu_timings t = {0};
    t.count = GPU_TIMINGS_KEPT + 2;
    gpu_timings_add(&t, 1, 1.5);
    gpu_timings_add(&t, 3, 2.0);
    gpu_timings_add(&t, 3, 0.25); /* CPU work beside the GPU time: adds up */
    gpu_timings_add(&t, GPU_TIMINGS_KEPT + 2, 8.0); /* beyond the kept ones: summed only */
    assert_true(t.ms[0] == 1.5 && t.ms[1] == 0.0 && t.ms[2] == 2.25);
    assert_true(t.total_ms == 11.75);
    assert_int_equal(t.arrived, 0); /* adding is not arriving */
    for (int i = 0; i < GPU_TIMINGS_KEPT; i++)
        assert_false(t.known[i]);
}

static void test_report_lists_times_and_nulls(void **state)
{
    struct session_stats st = {.command = "render", .device = "test"};
    st.views = 3;
    st.view_times.count = 3;
    st.view_times.ms[0] = 1.5;
    st.view_times.known[0] = true;
    st.view_times.ms[2] = 2.25;
    st.view_times.known[2] = true;
    st.light_builds = 1;
    st.build_times.count = 1;
    const char *path = test_tmp_path("stats.json");
    assert_true(session_stats_write(&st, path));
    char *text = file_read_all(path, NULL);
    assert_non_null(text);
    assert_non_null(strstr(text, "\"views\": 3,"));
    assert_non_null(strstr(text, "\"view_ms\": [1.5000, null, 2.2500],"));
    assert_non_null(strstr(text, "\"light_map_builds\": 1,"));
    assert_non_null(strstr(text, "\"build_ms\": [null],"));
    free(text);

    /* More than the kept number: the list stops at GPU_TIMINGS_KEPT entries. */
    st.view_times.count = GPU_TIMINGS_KEPT + 5;
    for (int i = 0; i < GPU_TIMINGS_KEPT; i++)
        st.view_times.known[i] = true;
    assert_true(session_stats_write(&st, path));
    text = file_read_all(path, NULL);
    const char *list = strstr(text, "\"view_ms\": [");
    assert_non_null(list);
    int entries = 1;
    for (const char *p = list; *p != ']'; p++)
        entries += *p == ',';
    assert_int_equal(entries, GPU_TIMINGS_KEPT);
    free(text);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_timings_add_by_number),
        cmocka_unit_test(test_report_lists_times_and_nulls),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
