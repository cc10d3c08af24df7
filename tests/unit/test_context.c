/* The context backend table as a contract, with a recording backend and no GL: the public
 * calls reach the backend's entries, and an entry a backend leaves NULL is a no-op. */
#include "testutil.h"

#include <string.h>

#include "gpu/context_impl.h"

static struct {
    int make_current, swap_interval, last_interval;
    struct gpu_context *ctx;
} calls;

static void record_make_current(struct gpu_context *ctx)
{
    calls.make_current++;
    calls.ctx = ctx;
}

static void record_swap_interval(struct gpu_context *ctx, int interval)
{
    /* The backend is called with its context made current first. */
    assert_ptr_equal(calls.ctx, ctx);
    assert_int_equal(calls.make_current, calls.swap_interval + 1);
    calls.swap_interval++;
    calls.last_interval = interval;
}

static const struct gpu_context_impl windowed = {
    .name = "recording",
    .make_current = record_make_current,
    .swap_interval = record_swap_interval,
};

static const struct gpu_context_impl headless = {
    .name = "glfw", /* a name decides nothing: only the table's entries do */
    .make_current = record_make_current,
};

static void test_swap_interval_goes_through_the_table(void **state)
{
    memset(&calls, 0, sizeof(calls));
    struct gpu_context a = {.impl = &windowed}, b = {.impl = &windowed};
    gpu_context_swap_interval(&a, 0);
    gpu_context_swap_interval(&b, 1);
    assert_int_equal(calls.swap_interval, 2);
    assert_int_equal(calls.make_current, 2);
    assert_ptr_equal(calls.ctx, &b);
    assert_int_equal(calls.last_interval, 1);
}

static void test_swap_interval_without_entry_is_a_no_op(void **state)
{
    memset(&calls, 0, sizeof(calls));
    struct gpu_context c = {.impl = &headless};
    gpu_context_swap_interval(&c, 1);
    gpu_context_swap_interval(NULL, 1);
    assert_int_equal(calls.swap_interval, 0);
    assert_int_equal(calls.make_current, 0); /* headless: not even made current */
}

static void test_real_backends(void **state)
{
    /* The window backend sets swap intervals; the headless one has none to set. */
    assert_non_null(gpu_context_glfw_impl.swap_interval);
    assert_null(gpu_context_egl_impl.swap_interval);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_swap_interval_goes_through_the_table),
        cmocka_unit_test(test_swap_interval_without_entry_is_a_no_op),
        cmocka_unit_test(test_real_backends),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
