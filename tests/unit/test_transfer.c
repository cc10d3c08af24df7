/* Transfer functions: editing, evaluation, and their files (round trip, corrupt files refused
 * with file:line while the current function is kept, a failed save keeping the old file). */
#include "testutil.h"

#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>

#include "common/log.h"
#include "config/transfer_file.h"
#include "optics/transfer.h"

static void test_eval_and_edit(void **state)
{
    struct transfer_function tf;
    transfer_defaults(&tf, TRANSFER_FIELD_QVAPOR);
    /* alpha: (0, 0), (0.3, 0), (1, 0.5): linear in between, clamped outside. */
    assert_float_equal(transfer_eval(&tf, TRANSFER_ALPHA, 0.25f), 0.0f, 1e-6);
    assert_float_equal(transfer_eval(&tf, TRANSFER_ALPHA, 0.65f), 0.25f, 1e-6);
    assert_float_equal(transfer_eval(&tf, TRANSFER_ALPHA, 2.0f), 0.5f, 1e-6);
    int i = transfer_add_point(&tf, TRANSFER_ALPHA, 0.6f, 1.0f);
    assert_int_equal(i, 2); /* sorted between 0.3 and 1 */
    assert_float_equal(transfer_eval(&tf, TRANSFER_ALPHA, 0.6f), 1.0f, 1e-6);
    i = transfer_move_point(&tf, TRANSFER_ALPHA, i, 0.1f, 0.2f);
    assert_int_equal(i, 1); /* moved before 0.3: re-sorted */
    assert_float_equal(tf.points[TRANSFER_ALPHA][1].x, 0.1f, 1e-6);
    assert_true(transfer_valid(&tf, NULL, 0));
    assert_true(transfer_delete_point(&tf, TRANSFER_ALPHA, 1));
    assert_int_equal(tf.count[TRANSFER_ALPHA], 3);
    /* A channel keeps one point. */
    assert_int_equal(tf.count[TRANSFER_BLUE], 1);
    assert_false(transfer_delete_point(&tf, TRANSFER_BLUE, 0));
    /* Values are clamped into [0, 1]. */
    i = transfer_add_point(&tf, TRANSFER_RED, 1.5f, -3.0f);
    assert_float_equal(tf.points[TRANSFER_RED][i].x, 1.0f, 0);
    assert_float_equal(tf.points[TRANSFER_RED][i].v, 0.0f, 0);
    float rgba[4];
    transfer_eval_rgba(&tf, tf.hi, rgba); /* x = 1 */
    assert_float_equal(rgba[TRANSFER_ALPHA], 0.5f, 1e-6);
}

static void test_round_trip(void **state)
{
    struct transfer_function tf, back;
    transfer_defaults(&tf, TRANSFER_FIELD_CONDENSATE);
    snprintf(tf.name, sizeof(tf.name), "odd \"name\" \\ here");
    tf.lo = 1e-5;
    tf.hi = 0.0031234567;
    tf.density = 0.0123456789;
    transfer_add_point(&tf, TRANSFER_GREEN, 0.3333333f, 0.7777777f);
    transfer_add_point(&tf, TRANSFER_ALPHA, 0.123456789f, 0.987654321f);
    const char *path = test_tmp_path("round.cfg");
    assert_true(transfer_file_save(path, &tf));
    memset(&back, 0x55, sizeof(back));
    assert_true(transfer_file_load(path, &back));
    assert_true(transfer_equal(&tf, &back));
}

/* A corrupt file: refused with FILE:LINE and the reason; the current function is kept. */
static void expect_refused(const char *name, const char *text, const char *needle)
{
    const char *path = test_write_file(name, text);
    char saved_path[512];
    snprintf(saved_path, sizeof(saved_path), "%s", path);
    struct transfer_function tf, before;
    transfer_defaults(&tf, TRANSFER_FIELD_QVAPOR);
    transfer_add_point(&tf, TRANSFER_RED, 0.4f, 0.4f);
    before = tf;
    enum log_level level = log_get_level();
    log_set_level(LOG_NONE);
    bool ok = transfer_file_load(saved_path, &tf);
    log_set_level(level);
    assert_false(ok);
    assert_true(transfer_equal(&tf, &before));
    const char *msg = log_last_error();
    if (!strstr(msg, needle)) {
        fprintf(stderr, "message \"%s\" lacks \"%s\"\n", msg, needle);
        fail();
    }
    assert_non_null(strstr(msg, saved_path));
}

static void test_corrupt_refused(void **state)
{
    expect_refused("syntax.cfg",
                   "transfer = {\n  name = \"x\";\n  field = \"qvapor\";\n"
                   "  range = [0.0, 1.0;\n};\n",
                   "syntax.cfg:4:");
    expect_refused("truncated.cfg", "transfer = {\n  name = \"x\";\n  field = \"qva",
                   "truncated.cfg:");
    expect_refused("badpoint.cfg",
                   "transfer = {\n field = \"qvapor\";\n range = [0.0, 0.02];\n density = 0.001;\n"
                   " red = ([0.0, 0.5]);\n green = ([0.0, 0.5]);\n blue = ([0.0, 0.5]);\n"
                   " alpha = ([0.0, 0.0],\n          [1.5, 0.2]);\n};\n",
                   "badpoint.cfg:9: transfer.alpha[1]: expected x and value in [0, 1]");
    expect_refused("order.cfg",
                   "transfer = {\n field = \"qvapor\";\n range = [0.0, 0.02];\n density = 0.001;\n"
                   " red = ([0.5, 0.5], [0.2, 0.1]);\n green = ([0.0, 0.5]);\n"
                   " blue = ([0.0, 0.5]);\n alpha = ([0.0, 0.0]);\n};\n",
                   "order.cfg:5: transfer.red[1]: expected x >= 0.5");
    expect_refused("field.cfg",
                   "transfer = {\n field = \"pressure\";\n range = [0.0, 0.02];\n};\n",
                   "field.cfg:2: transfer.field: expected \"qvapor\", \"condensate\", "
                   "\"temperature\" or \"wind\"");
    expect_refused("range.cfg",
                   "transfer = {\n field = \"qvapor\";\n range = [0.02, 0.0];\n};\n",
                   "range.cfg:3: transfer.range: expected [lo, hi]");
    expect_refused("missing.cfg",
                   "transfer = {\n field = \"qvapor\";\n range = [0.0, 0.02];\n density = 0.1;\n"
                   " red = ([0.0, 0.5]);\n};\n",
                   "transfer.green: missing");
    expect_refused("nogroup.cfg", "name = \"x\";\n", "expected a group");
    expect_refused("binary.cfg", "\x01\x02\x03garbage\xff", "binary.cfg");
    /* A file that does not exist. */
    struct transfer_function tf;
    transfer_defaults(&tf, TRANSFER_FIELD_QVAPOR);
    log_set_level(LOG_NONE);
    assert_false(transfer_file_load(test_tmp_path("nope.cfg"), &tf));
    log_set_level(LOG_INFO);
    assert_non_null(strstr(log_last_error(), "nope.cfg"));
}

static bool read_text(const char *path, char *buf, size_t size)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return false;
    size_t n = fread(buf, 1, size - 1, f);
    buf[n] = '\0';
    fclose(f);
    return true;
}

static void test_failed_save_keeps_old(void **state)
{
    char dir[512], path[600], cmd[700], before[4096], after[4096];
    snprintf(dir, sizeof(dir), "%s", test_tmp_path("locked"));
    assert_int_equal(mkdir(dir, 0777), 0);
    snprintf(path, sizeof(path), "%s/tf-1.cfg", dir);
    struct transfer_function tf;
    transfer_defaults(&tf, TRANSFER_FIELD_QVAPOR);
    assert_true(transfer_file_save(path, &tf));
    assert_true(read_text(path, before, sizeof(before)));
    transfer_add_point(&tf, TRANSFER_ALPHA, 0.9f, 0.9f);

    snprintf(cmd, sizeof(cmd), "chattr +i '%s' 2>/dev/null", dir);
    bool locked = system(cmd) == 0;
    log_set_level(LOG_NONE);
    bool ok;
    if (locked) {
        ok = transfer_file_save(path, &tf); /* cannot create the temporary file */
        snprintf(cmd, sizeof(cmd), "chattr -i '%s'", dir);
        assert_int_equal(system(cmd), 0);
    } else {
        /* No chattr here: a file size limit makes the write itself fail. */
        struct rlimit old, small = {.rlim_cur = 64, .rlim_max = RLIM_INFINITY};
        getrlimit(RLIMIT_FSIZE, &old);
        small.rlim_max = old.rlim_max;
        signal(SIGXFSZ, SIG_IGN);
        setrlimit(RLIMIT_FSIZE, &small);
        ok = transfer_file_save(path, &tf);
        setrlimit(RLIMIT_FSIZE, &old);
    }
    log_set_level(LOG_INFO);
    assert_false(ok);
    assert_non_null(strstr(log_last_error(), "tf-1.cfg"));
    assert_true(read_text(path, after, sizeof(after)));
    assert_string_equal(before, after);
    struct transfer_function back;
    assert_true(transfer_file_load(path, &back));
    assert_int_equal(back.count[TRANSFER_ALPHA], 3);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_eval_and_edit),
        cmocka_unit_test(test_round_trip),
        cmocka_unit_test(test_corrupt_refused),
        cmocka_unit_test(test_failed_save_keeps_old),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
