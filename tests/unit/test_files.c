/* common: reading text files (regular files only, a size cap) and writing files atomically. */
#include "testutil.h"

#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "common/log.h"

/* A read that waits on a FIFO would hang the test: the alarm ends it as a failure instead. */
static void fail_on_alarm(int sig)
{
    (void)sig;
    static const char msg[] = "test_files: a read blocked for 10 s\n";
    if (write(2, msg, sizeof(msg) - 1) < 0)
        _exit(2);
    _exit(1);
}

static void expect_refused(const char *path, size_t max, const char *word)
{
    char why[160] = "";
    size_t len = 12345;
    char *text = file_read_text(path, max, &len, why, sizeof(why));
    assert_null(text);
    if (!strstr(why, word)) {
        fprintf(stderr, "reason \"%s\" lacks \"%s\"\n", why, word);
        fail();
    }
}

static void test_read_regular(void **state)
{
    const char *path = test_write_file("ten.txt", "0123456789");
    char why[160];
    size_t len = 0;
    char *text = file_read_text(path, 10, &len, why, sizeof(why));
    assert_non_null(text);
    assert_int_equal(len, 10);
    assert_string_equal(text, "0123456789");
    free(text);
    /* One byte over the cap is refused, with the cap in the message. */
    expect_refused(path, 9, "larger than the 9 bytes");
    /* An empty file is an empty text. */
    text = file_read_text(test_write_file("empty.txt", ""), 10, &len, why, sizeof(why));
    assert_non_null(text);
    assert_int_equal(len, 0);
    free(text);
}

static void test_refuse_big_file_unread(void **state)
{
    /* A sparse file one byte over FILE_TEXT_MAX: refused from its size, before any read. */
    const char *path = test_tmp_path("big.cfg");
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    assert_int_equal(ftruncate(fileno(f), (off_t)FILE_TEXT_MAX + 1), 0);
    fclose(f);
    unsigned errors = log_error_count();
    log_set_level(LOG_NONE);
    assert_null(file_read_all(path, NULL));
    log_set_level(LOG_INFO);
    assert_int_equal(log_error_count(), errors + 1);
    assert_non_null(strstr(log_last_error(), path));
    assert_non_null(strstr(log_last_error(), "64 MiB"));
}

static void test_refuse_devices_fifos_folders(void **state)
{
    signal(SIGALRM, fail_on_alarm);
    alarm(10);
    /* /dev/zero never ends; a FIFO without a writer would block the open for ever. */
    expect_refused("/dev/zero", FILE_TEXT_MAX, "not a regular file (a character device)");
    const char *fifo = test_tmp_path("fifo");
    assert_int_equal(mkfifo(fifo, 0600), 0);
    expect_refused(fifo, FILE_TEXT_MAX, "not a regular file (a FIFO)");
    expect_refused(test_tmpdir(), FILE_TEXT_MAX, "not a regular file (a folder)");
    expect_refused(test_tmp_path("missing"), FILE_TEXT_MAX, "No such file");
    char why[160];
    assert_int_equal(file_open_regular(fifo, why, sizeof(why)), -1);
    alarm(0);
}

static char *contents(const char *path)
{
    char why[160];
    char *t = file_read_text(path, 1 << 20, NULL, why, sizeof(why));
    assert_non_null(t);
    return t;
}

static int mode_of(const char *path)
{
    struct stat st;
    assert_int_equal(stat(path, &st), 0);
    return (int)(st.st_mode & 07777);
}

/* No PATH.tmp* beside PATH. */
static void no_temporaries(const char *dir)
{
    char cmd[600];
    snprintf(cmd, sizeof(cmd), "ls '%s' | grep -q '[.]tmp'", dir);
    assert_int_not_equal(system(cmd), 0);
}

static void test_write_keeps_mode_and_refuses_read_only(void **state)
{
    char path[512];
    snprintf(path, sizeof(path), "%s", test_write_file("tf.cfg", "old\n"));
    /* A file's mode is kept across a save (it was reset to 0666 less the umask). */
    assert_int_equal(chmod(path, 0640), 0);
    assert_true(file_write_atomic(path, "new\n", 4));
    assert_int_equal(mode_of(path), 0640);
    char *t = contents(path);
    assert_string_equal(t, "new\n");
    free(t);
    /* A read-only file is not replaced (it was, and became 0644). */
    assert_int_equal(chmod(path, 0444), 0);
    unsigned errors = log_error_count();
    log_set_level(LOG_NONE);
    assert_false(file_write_atomic(path, "newer\n", 6));
    log_set_level(LOG_INFO);
    assert_int_equal(log_error_count(), errors + 1);
    assert_non_null(strstr(log_last_error(), path));
    assert_non_null(strstr(log_last_error(), "read-only (mode 0444): not replaced"));
    assert_int_equal(mode_of(path), 0444);
    t = contents(path);
    assert_string_equal(t, "new\n");
    free(t);
    no_temporaries(test_tmpdir());
    /* Nor is a folder. */
    log_set_level(LOG_NONE);
    assert_false(file_write_atomic(test_tmpdir(), "x", 1));
    log_set_level(LOG_INFO);
    assert_non_null(strstr(log_last_error(), "not a regular file"));
}

static void test_write_through_symlink(void **state)
{
    /* A save over a symbolic link replaces the file it points to; the link stays (it became a
     * regular file). */
    char real[512], link[512];
    snprintf(real, sizeof(real), "%s", test_write_file("real.cfg", "old\n"));
    snprintf(link, sizeof(link), "%s", test_tmp_path("link.cfg"));
    assert_int_equal(symlink("real.cfg", link), 0);
    assert_true(file_write_atomic(link, "through\n", 8));
    struct stat st;
    assert_int_equal(lstat(link, &st), 0);
    assert_true(S_ISLNK(st.st_mode));
    char *t = contents(real);
    assert_string_equal(t, "through\n");
    free(t);
    /* A link to nothing is refused. */
    char dangling[512];
    snprintf(dangling, sizeof(dangling), "%s", test_tmp_path("dangling.cfg"));
    assert_int_equal(symlink("nowhere/x.cfg", dangling), 0);
    log_set_level(LOG_NONE);
    assert_false(file_write_atomic(dangling, "x", 1));
    log_set_level(LOG_INFO);
    assert_non_null(strstr(log_last_error(), "a symbolic link to a file that does not exist"));
    assert_int_equal(lstat(dangling, &st), 0);
    assert_true(S_ISLNK(st.st_mode));
    /* A link to a read-only file: refused like the file. */
    assert_int_equal(chmod(real, 0444), 0);
    log_set_level(LOG_NONE);
    assert_false(file_write_atomic(link, "x", 1));
    log_set_level(LOG_INFO);
    assert_non_null(strstr(log_last_error(), "read-only"));
    no_temporaries(test_tmpdir());
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_read_regular),
        cmocka_unit_test(test_refuse_big_file_unread),
        cmocka_unit_test(test_refuse_devices_fifos_folders),
        cmocka_unit_test(test_write_keeps_mode_and_refuses_read_only),
        cmocka_unit_test(test_write_through_symlink),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
