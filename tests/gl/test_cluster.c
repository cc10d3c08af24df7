/* A CAVE on an MPI cluster (mpirun --oversubscribe -np 4 on loopback): the ranks' walls equal
 * the single process's views, still and frame by frame through a script that plays, moves the
 * sun and toggles a species in the menu; --check-sync passes, and fails naming the rank that
 * was given another setting; a rank that cannot start or is killed ends the job quickly with
 * the rank named; a job of more ranks than walls is refused; --stats gathers every rank's.
 * Skipped without MPI in the build or without mpirun. */
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "testutil.h"

#include "cluster/cluster.h"
#include "common/log.h"
#include "gpu/gpu.h"
#include "render/image.h"

static const char *anvil;
static char dir[512];
static const char *cave = "--display " ANVIL_SOURCE_DIR "/displays/cave4.cfg --format pfm";
static const char *small = "--set render.height=40 --set lightmap.resolution=[24,24,24]";
static const char *const walls[] = {"front-left",  "front-right", "left-left",  "left-right",
                                    "right-left",  "right-right", "floor-left", "floor-right"};

/* Runs CMD in the test folder with stderr to err.txt; its exit status. */
static int shell(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
static int shell(const char *fmt, ...)
{
    char args[3072], cmd[4096];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(args, sizeof(args), fmt, ap);
    va_end(ap);
    snprintf(cmd, sizeof(cmd), "cd '%s' && %s 2>err.txt", dir, args);
    int st = system(cmd);
    st = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
    if (st != 0 && getenv("ANVIL_TEST_VERBOSE")) {
        snprintf(cmd, sizeof(cmd), "cat '%s/err.txt'", dir);
        print_message("exit %d: %s\n", st, args);
        (void)!system(cmd);
    }
    return st;
}

/* mpirun with N ranks of anvil ARGS (the job's status). */
#define MPIRUN "mpirun --oversubscribe --bind-to none"
static int mpi(int n, const char *args)
{
    return shell(MPIRUN " -np %d '%s' --quiet %s", n, anvil, args);
}

static bool err_has(const char *text)
{
    char path[1024], *buf;
    snprintf(path, sizeof(path), "%s/err.txt", dir);
    buf = file_read_all(path, NULL);
    bool has = buf && strstr(buf, text);
    if (!has)
        print_message("err.txt lacks \"%s\":\n%s\n", text, buf ? buf : "(none)");
    free(buf);
    return has;
}

/* The largest difference between PFMs A and B of the test folder (INFINITY: unreadable or of
 * different sizes). */
static double diff(const char *a, const char *b)
{
    char pa[1024], pb[1024];
    snprintf(pa, sizeof(pa), "%s/%s", dir, a);
    snprintf(pb, sizeof(pb), "%s/%s", dir, b);
    struct image x = {0}, y = {0};
    double d = INFINITY;
    if (image_read_pfm(pa, &x) && image_read_pfm(pb, &y) && x.width == y.width &&
        x.height == y.height) {
        d = 0.0;
        for (size_t i = 0; i < (size_t)x.width * x.height * 4; i++)
            d = fmax(d, fabs((double)x.rgba[i] - y.rgba[i]));
    }
    image_finish(&x);
    image_finish(&y);
    return d;
}

static bool exists(const char *name)
{
    char path[1024];
    snprintf(path, sizeof(path), "%s/%s", dir, name);
    return access(path, F_OK) == 0;
}

static void test_still_walls_equal_one_process(void **state)
{
    (void)state;
    char args[1024];
    assert_int_equal(shell("mkdir -p one four && '%s' --quiet render %s %s -o one/", anvil, cave,
                           small),
                     0);
    snprintf(args, sizeof(args), "render %s %s -o four/ --check-sync --stats four.json", cave,
             small);
    assert_int_equal(mpi(4, args), 0);
    for (size_t i = 0; i < sizeof(walls) / sizeof(walls[0]); i++) {
        char a[128], b[128];
        snprintf(a, sizeof(a), "one/%s.pfm", walls[i]);
        snprintf(b, sizeof(b), "four/%s.pfm", walls[i]);
        double d = diff(a, b);
        if (d > 1e-6)
            fail_msg("%s: the cluster's differs from one process's by %g", walls[i], d);
    }
    assert_true(exists("one/contact.pfm"));
    assert_false(exists("four/contact.pfm")); /* no rank has every wall */
    /* --stats: every rank's, with its walls, in rank 0's file. */
    char *json = file_read_all(test_tmp_path("four.json"), NULL);
    assert_non_null(json);
    assert_non_null(strstr(json, "\"cluster_ranks\": 4"));
    assert_non_null(strstr(json, "\"rank\": 3"));
    assert_non_null(strstr(json, "\"walls\": \"floor\""));
    assert_non_null(strstr(json, "\"sync_ms\""));
    free(json);
}

/* A head that moves (a path, sampled on rank 0 and sent): the walls still equal one process's
 * at the same moment, and differ from the fixed head's. */
static void test_moving_head_is_rank_0s(void **state)
{
    (void)state;
    FILE *f = fopen(test_tmp_path("head.txt"), "w");
    fprintf(f, "0 0.0 1.6 0.5 0 0 0\n5 0.8 1.2 -0.5 40 -20 0\n");
    fclose(f);
    char args[1024];
    const char *head = "--set 'head.source=\"path\"' --set 'head.path=\"head.txt\"' --time 2.5";
    assert_int_equal(shell("mkdir -p h1 h4 && '%s' --quiet render %s %s %s -o h1/", anvil, cave,
                           small, head),
                     0);
    snprintf(args, sizeof(args), "render %s %s %s -o h4/ --check-sync", cave, small, head);
    assert_int_equal(mpi(4, args), 0);
    for (size_t i = 0; i < sizeof(walls) / sizeof(walls[0]); i++) {
        char a[128], b[128];
        snprintf(a, sizeof(a), "h1/%s.pfm", walls[i]);
        snprintf(b, sizeof(b), "h4/%s.pfm", walls[i]);
        double d = diff(a, b);
        if (d > 1e-6)
            fail_msg("%s: the cluster's differs from one process's by %g", walls[i], d);
    }
    /* The path moved the head: rank 3's floor is not the fixed head's floor. */
    assert_true(diff("h4/floor-left.pfm", "four/floor-left.pfm") > 1e-3);
}

static void test_script_frames_equal_one_process(void **state)
{
    (void)state;
    /* Play, move the sun, open the fields page and turn the cloud off, pause. */
    FILE *f = fopen(test_tmp_path("script.txt"), "w");
    fprintf(f, "fps 10\n0 key play\n3 key sun-left\n4 key sun-up\n5 aim tab.fields\n"
               "5 button trigger down\n6 button trigger up\n7 aim fields.cloud\n"
               "7 button trigger down\n8 button trigger up\n10 key play\n11 key sun-down\n");
    fclose(f);
    char args[1024];
    const char *common = "series.cfg --input script.txt --menu --set "
                         "'effects.temporal=\"off\"'";
    assert_int_equal(shell("mkdir -p s1 s4 && '%s' --quiet render %s %s %s -o s1/f-%%02d.pfm",
                           anvil, common, cave, small),
                     0);
    snprintf(args, sizeof(args), "render %s %s %s -o s4/f-%%02d.pfm --check-sync", common, cave,
             small);
    assert_int_equal(mpi(4, args), 0);
    int frames = 0;
    for (int n = 0; n < 100; n++) {
        char a[128], b[128];
        snprintf(a, sizeof(a), "s1/%s-f-%02d.pfm", walls[0], n);
        if (!exists(a))
            break;
        frames++;
        for (size_t i = 0; i < sizeof(walls) / sizeof(walls[0]); i++) {
            snprintf(a, sizeof(a), "s1/%s-f-%02d.pfm", walls[i], n);
            snprintf(b, sizeof(b), "s4/%s-f-%02d.pfm", walls[i], n);
            double d = diff(a, b);
            if (d > 1e-6)
                fail_msg("frame %d, %s: the cluster's differs by %g", n, walls[i], d);
        }
    }
    assert_true(frames >= 12);
    /* The script changed the pictures: the sun and the species are not lost on the way. */
    assert_true(diff("s1/front-left-f-02.pfm", "s1/front-left-f-09.pfm") > 1e-3);
}

static void test_check_sync_names_the_rank(void **state)
{
    (void)state;
    char args[2048];
    snprintf(args, sizeof(args),
             MPIRUN " -np 3 '%s' --quiet render %s %s -o sync/ --check-sync : -np 1 '%s' "
                    "--quiet render %s %s --set render.exposure=2 -o sync/ --check-sync",
             anvil, cave, small, anvil, cave, small);
    assert_int_not_equal(shell("mkdir -p sync && %s", args), 0);
    assert_true(err_has("rank 3 is out of step"));
    /* Without --check-sync the same job draws (the check is what finds it). */
    snprintf(args, sizeof(args),
             MPIRUN " -np 3 '%s' --quiet render %s %s -o sync/ : -np 1 '%s' "
                    "--quiet render %s %s --set render.exposure=2 -o sync/",
             anvil, cave, small, anvil, cave, small);
    assert_int_equal(shell("%s", args), 0);
}

/* anvil run under Xvfb, rank 1 reading its disk slowly while the series plays: every rank
 * shows the same step every frame (--check-sync compares the steps shown), the cluster held
 * the old step while rank 1 loaded, and playback went on past the held steps.  Nothing is
 * prefetched (data.prefetch = 0: a slow start, under a sanitizer, would otherwise let rank 1
 * load every step before playback begins), and its 1.2 s a step is longer than a frame of this
 * machine under the load of other tests, so a frame must find it loading the step wanted; how
 * many steps 600 frames reach depends on the frame time.  The step changes are swaps of steps
 * readied between frames (staged playback). */
static void test_slow_rank_holds_the_step(void **state)
{
    (void)state;
    if (system("command -v xvfb-run >/dev/null 2>&1") != 0)
        skip();
    FILE *f = fopen(test_tmp_path("play.txt"), "w");
    fprintf(f, "fps 10\n0 key play\n600 key quit\n");
    fclose(f);
    const char *args = "run series.cfg --display " ANVIL_SOURCE_DIR "/displays/cave4.cfg "
                       "--input play.txt --check-sync --stats held.json "
                       "--set display.window_size=[48,48] --set walls.[0].monitor=-1 "
                       "--set lightmap.resolution=[16,16,16] --set data.prefetch=0";
    assert_int_equal(shell("xvfb-run -a -s '-screen 0 640x480x24' " MPIRUN
                           " -np 1 -x DISPLAY '%s' --quiet %s : -np 1 -x DISPLAY "
                           "-x ANVIL_TEST_LOAD_DELAY_MS=1200 '%s' --quiet %s",
                           anvil, args, anvil, args),
                     0);
    char *json = file_read_all(test_tmp_path("held.json"), NULL);
    assert_non_null(json);
    const char *held = strstr(json, "\"frames_held\": ");
    assert_non_null(held);
    int n = atoi(held + strlen("\"frames_held\": "));
    print_message("frames held for rank 1: %d\n", n);
    if (n <= 0)
        free(json);
    assert_true(n > 0);
    const char *step = strstr(json, "\"time_step\": ");
    assert_non_null(step);
    assert_true(atoi(step + strlen("\"time_step\": ")) >= 1); /* moved on after a hold */
    /* The step changes the hold let through were swaps of steps readied between frames. */
    const char *swaps = strstr(json, "\"volume_swaps\": ");
    assert_non_null(swaps);
    assert_true(atoi(swaps + strlen("\"volume_swaps\": ")) >= 1);
    free(json);
}

static void test_refusals(void **state)
{
    (void)state;
    char args[1024];
    snprintf(args, sizeof(args), "render %s %s -o five/", cave, small);
    assert_int_not_equal(shell("mkdir -p five && " MPIRUN " -np 5 '%s' --quiet %s", anvil, args),
                         0);
    assert_true(err_has("rank 4 of 5 has no wall to draw"));
    assert_int_not_equal(mpi(2, "render --set render.height=8 -o x.png"), 0);
    assert_true(err_has("give --display"));
    /* One rank cannot start (its scene file is not on its disk): all stop, it is named. */
    snprintf(args, sizeof(args),
             MPIRUN " -np 3 '%s' --quiet render %s %s -o five/ : -np 1 '%s' --quiet render "
                    "missing.cfg %s %s -o five/",
             anvil, cave, small, anvil, cave, small);
    double t = time_now_ms();
    assert_int_not_equal(shell("%s", args), 0);
    assert_true(err_has("rank 3 could not start"));
    assert_true(time_now_ms() - t < 60000.0);
}

/* Whether PID descends from ANCESTOR (other tests may run MPI jobs of their own). */
static bool descends_from(pid_t pid, pid_t ancestor)
{
    for (int depth = 0; depth < 8 && pid > 1; depth++) {
        char path[64], stat[1024];
        snprintf(path, sizeof(path), "/proc/%d/stat", (int)pid);
        FILE *f = fopen(path, "r");
        size_t n = f ? fread(stat, 1, sizeof(stat) - 1, f) : 0;
        if (f)
            fclose(f);
        stat[n] = '\0';
        const char *close = strrchr(stat, ')'); /* the name may hold spaces */
        int ppid = 0;
        if (!close || sscanf(close + 1, " %*c %d", &ppid) != 1)
            return false;
        if (ppid == ancestor)
            return true;
        pid = ppid;
    }
    return false;
}

/* The pid of rank RANK of the running job JOB (0: none yet). */
static pid_t rank_pid(int rank, pid_t job)
{
    char cmd[512], want[64];
    snprintf(want, sizeof(want), "OMPI_COMM_WORLD_RANK=%d", rank);
    snprintf(cmd, sizeof(cmd), "pgrep -x anvil");
    FILE *p = popen(cmd, "r");
    int pid;
    pid_t found = 0;
    while (p && fscanf(p, "%d", &pid) == 1) {
        if (!descends_from(pid, job))
            continue;
        char path[64], env[65536];
        snprintf(path, sizeof(path), "/proc/%d/environ", pid);
        FILE *e = fopen(path, "rb");
        size_t n = e ? fread(env, 1, sizeof(env) - 1, e) : 0;
        if (e)
            fclose(e);
        for (size_t i = 0; i < n; i += strlen(env + i) + 1) {
            env[n] = '\0';
            if (strcmp(env + i, want) == 0)
                found = pid;
        }
    }
    if (p)
        pclose(p);
    return found;
}

static void test_killed_rank_ends_the_job(void **state)
{
    (void)state;
    /* A long script: the job is still drawing when rank 2 is killed. */
    FILE *f = fopen(test_tmp_path("long.txt"), "w");
    fprintf(f, "fps 10\n0 key play\n100000 key play\n");
    fclose(f);
    char cmd[2048];
    snprintf(cmd, sizeof(cmd),
             "cd '%s' && exec " MPIRUN " -np 4 '%s' --quiet render series.cfg --input long.txt "
             "%s --set render.height=16 --set lightmap.resolution=[16,16,16] -o kill/ "
             "2>kill.txt",
             dir, anvil, cave);
    assert_int_equal(shell("mkdir -p kill"), 0);
    pid_t job = fork();
    if (job == 0) {
        execl("/bin/sh", "sh", "-c", cmd, (char *)NULL);
        _exit(127);
    }
    pid_t victim = 0;
    for (int i = 0; i < 600 && !victim; i++) {
        usleep(50000);
        victim = rank_pid(2, job);
    }
    assert_true(victim > 0);
    sleep(3); /* in the frame loop */
    kill(victim, SIGKILL);
    double t = time_now_ms();
    int st = 0;
    pid_t done = 0;
    while ((done = waitpid(job, &st, WNOHANG)) == 0 && time_now_ms() - t < 30000.0)
        usleep(50000);
    if (done == 0) {
        kill(job, SIGKILL);
        waitpid(job, &st, 0);
        fail_msg("the job did not end within 30 s of rank 2's death");
    }
    print_message("the job ended %.1f s after rank 2 was killed\n", (time_now_ms() - t) * 1e-3);
    assert_true(time_now_ms() - t < 10000.0);
    assert_false(WIFEXITED(st) && WEXITSTATUS(st) == 0);
    char path[1024];
    snprintf(path, sizeof(path), "%s/kill.txt", dir);
    char *err = file_read_all(path, NULL);
    assert_non_null(err);
    if (!strstr(err, "rank 2"))
        fail_msg("the job's messages do not name rank 2:\n%s", err);
    free(err);
}

int main(void)
{
    gpu_context_destroy(test_gl_context_or_skip());
    anvil = getenv("ANVIL_BIN");
    if (!anvil || !cluster_available()) {
        printf("built without MPI: skipping\n");
        return TEST_SKIP;
    }
    if (system("command -v mpirun >/dev/null 2>&1") != 0) {
        printf("no mpirun: skipping\n");
        return TEST_SKIP;
    }
    setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 1);
    setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 1);
    setenv("OMPI_MCA_btl", "self,tcp", 1);            /* loopback only */
    setenv("OMPI_MCA_btl_tcp_if_include", "lo", 1);
    setenv("OMPI_MCA_oob_tcp_if_include", "lo", 1);
    snprintf(dir, sizeof(dir), "%s", test_tmpdir());
    if (shell("'%s' --quiet synth -o series.nc --steps 4 --size 16x16x8 --extent 16x16x8",
              anvil) != 0)
        return 1;
    FILE *f = fopen(test_tmp_path("series.cfg"), "w");
    fprintf(f, "scene = { kind = \"data\"; };\n"
               "data = { format = \"wrf\"; files = [\"series.nc\"]; };\n"
               "playback = { speed = 1.0; loop = false; };\n");
    fclose(f);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_still_walls_equal_one_process),
        cmocka_unit_test(test_moving_head_is_rank_0s),
        cmocka_unit_test(test_script_frames_equal_one_process),
        cmocka_unit_test(test_check_sync_names_the_rank),
        cmocka_unit_test(test_slow_rank_holds_the_step),
        cmocka_unit_test(test_refusals),
        cmocka_unit_test(test_killed_rank_ends_the_job),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
