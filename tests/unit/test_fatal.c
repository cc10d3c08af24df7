/* common/fatal: what a signal does to the process, in forked children: a crash inside a
 * library's scope is reported as the library's (exit 1 reading, 4 writing), one after the work
 * keeps the work's exit code, one of ours stays a crash; SIGINT, SIGTERM and SIGHUP exit
 * 128 + the signal; every time the tracked temporary files are removed.  With a graceful stop
 * asked for, the first stop signal is only recorded, a second one ends the process. */
#include "testutil.h"

#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "common/fatal.h"

enum what { CRASH_READING, CRASH_WRITING, CRASH_AT_EXIT, CRASH_OURS, STOP, GRACEFUL };

struct outcome {
    int status;      /* from waitpid */
    char err[2048];  /* the child's stderr */
    bool temp_gone;  /* the tracked file was removed */
    bool other_kept; /* an untracked file was not */
};

static struct outcome run_child(enum what what, int sig)
{
    struct outcome o = {0};
    char temp[512], other[512], errpath[512];
    snprintf(temp, sizeof(temp), "%s", test_tmp_path("out.nc.tmpAAAAAA"));
    snprintf(other, sizeof(other), "%s", test_tmp_path("untracked.tmp"));
    snprintf(errpath, sizeof(errpath), "%s", test_tmp_path("stderr.txt"));
    fclose(fopen(temp, "w"));
    fclose(fopen(other, "w"));
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        int fd = open(errpath, O_WRONLY | O_CREAT | O_TRUNC, 0600);
        dup2(fd, 2);
        /* The child's signals as a user's shell would leave them (not cmocka's). */
        const int all[] = {SIGINT, SIGTERM, SIGHUP, SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT};
        for (int i = 0; i < 8; i++)
            signal(all[i], SIG_DFL);
        fatal_install();
        fatal_track(other);
        fatal_untrack(other);
        fatal_track(temp);
        struct fatal_scope saved;
        switch (what) {
        case CRASH_READING:
            fatal_enter(&saved, "netCDF-C (with HDF5)", "reading", "/data/storm.nc", false);
            break;
        case CRASH_WRITING:
            fatal_enter(&saved, "netCDF-C (with HDF5)", "writing", "/data/ext.nc", true);
            break;
        case CRASH_AT_EXIT:
            fatal_exiting(4);
            break;
        case GRACEFUL:
            /* The first signal is recorded and the child goes on: it exits 50 + the signal
             * it saw; a second one ends it at once, as without a graceful stop. */
            fatal_stop_gracefully(true);
            raise(sig);
            if (fatal_stop_requested() != sig)
                _exit(98);
            if (sig == SIGHUP) /* the second signal, on SIGHUP's turn */
                raise(SIGTERM);
            _exit(50 + fatal_stop_requested());
        case CRASH_OURS:
        case STOP:
            /* a scope entered and left is no scope */
            fatal_enter(&saved, "libpng", "writing", "x.png", true);
            fatal_leave(&saved);
            break;
        }
        raise(sig);
        _exit(99); /* not reached */
    }
    assert_int_equal(waitpid(pid, &o.status, 0), pid);
    FILE *f = fopen(errpath, "r");
    assert_non_null(f);
    size_t n = fread(o.err, 1, sizeof(o.err) - 1, f);
    o.err[n] = '\0';
    fclose(f);
    struct stat st;
    o.temp_gone = stat(temp, &st) != 0;
    o.other_kept = stat(other, &st) == 0;
    return o;
}

static void expect_exit(const struct outcome *o, int code)
{
    if (!WIFEXITED(o->status) || WEXITSTATUS(o->status) != code) {
        fprintf(stderr, "status %#x, expected exit %d; stderr: %s\n", o->status, code, o->err);
        fail();
    }
    assert_true(o->temp_gone);
    assert_true(o->other_kept);
}

static void expect_err(const struct outcome *o, const char *word)
{
    if (!strstr(o->err, word)) {
        fprintf(stderr, "stderr \"%s\" lacks \"%s\"\n", o->err, word);
        fail();
    }
}

static void test_library_crash_reading(void **state)
{
    const int sigs[] = {SIGSEGV, SIGFPE, SIGBUS, SIGILL, SIGABRT};
    for (int i = 0; i < 5; i++) {
        struct outcome o = run_child(CRASH_READING, sigs[i]);
        expect_exit(&o, FATAL_EXIT_READING);
        expect_err(&o, "anvil: error: netCDF-C (with HDF5) crashed (SIG");
        expect_err(&o, ") reading /data/storm.nc: the file is damaged");
        expect_err(&o, "removed ");
        expect_err(&o, "out.nc.tmpAAAAAA");
    }
}

static void test_library_crash_writing(void **state)
{
    struct outcome o = run_child(CRASH_WRITING, SIGSEGV);
    expect_exit(&o, FATAL_EXIT_WRITING);
    expect_err(&o, "crashed (SIGSEGV) writing /data/ext.nc: the file could not be written");
}

static void test_crash_while_ending(void **state)
{
    /* HDF5's exit handler after a failed write: the work's exit code stands. */
    struct outcome o = run_child(CRASH_AT_EXIT, SIGSEGV);
    expect_exit(&o, 4);
    expect_err(&o, "a library crashed (SIGSEGV) while the program ended; its exit code 4 stands");
}

static void test_our_crash_stays_a_crash(void **state)
{
    struct outcome o = run_child(CRASH_OURS, SIGSEGV);
    assert_true(WIFSIGNALED(o.status));
    assert_int_equal(WTERMSIG(o.status), SIGSEGV);
    assert_true(o.temp_gone);
    assert_true(o.other_kept);
    expect_err(&o, "crashed (SIGSEGV); removed ");
}

static void test_interrupted(void **state)
{
    const int sigs[] = {SIGINT, SIGTERM, SIGHUP};
    const char *names[] = {"SIGINT", "SIGTERM", "SIGHUP"};
    for (int i = 0; i < 3; i++) {
        struct outcome o = run_child(STOP, sigs[i]);
        expect_exit(&o, 128 + sigs[i]);
        char want[64];
        snprintf(want, sizeof(want), "anvil: interrupted (%s); removed ", names[i]);
        expect_err(&o, want);
    }
}

static void test_stop_gracefully(void **state)
{
    (void)state;
    /* One signal: recorded, said, the temporary file left for the caller to finish. */
    const int sigs[] = {SIGINT, SIGTERM};
    const char *names[] = {"SIGINT", "SIGTERM"};
    for (int i = 0; i < 2; i++) {
        struct outcome o = run_child(GRACEFUL, sigs[i]);
        if (!WIFEXITED(o.status) || WEXITSTATUS(o.status) != 50 + sigs[i]) {
            fprintf(stderr, "status %#x; stderr: %s\n", o.status, o.err);
            fail();
        }
        assert_false(o.temp_gone);
        char want[96];
        snprintf(want, sizeof(want), "anvil: interrupted (%s): ending as if", names[i]);
        expect_err(&o, want);
    }
    /* A second signal ends the process as before: 128 + it, the temporary file removed. */
    struct outcome o = run_child(GRACEFUL, SIGHUP);
    expect_exit(&o, 128 + SIGTERM);
    expect_err(&o, "anvil: interrupted (SIGTERM); removed ");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_library_crash_reading),
        cmocka_unit_test(test_library_crash_writing),
        cmocka_unit_test(test_crash_while_ending),
        cmocka_unit_test(test_our_crash_stays_a_crash),
        cmocka_unit_test(test_interrupted),
        cmocka_unit_test(test_stop_gracefully),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
