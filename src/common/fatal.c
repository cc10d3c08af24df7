#include "common/fatal.h"

#include <errno.h>
#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define SLOTS 32
#define PATH_BYTES 1024

/* Temporary files: a slot is written while USED is 0, then USED set (release); the handler
 * reads the path only where it sees USED set (acquire). */
static struct {
    atomic_int claimed; /* the slot belongs to a caller */
    atomic_int used;    /* the path is complete: the handler may remove it */
    char path[PATH_BYTES];
} temps[SLOTS];

static _Thread_local struct fatal_scope scope;
static volatile sig_atomic_t exiting, exit_code;
static volatile sig_atomic_t graceful, stop_signal;

static const int crash_signals[] = {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT};
static const int stop_signals[] = {SIGINT, SIGTERM, SIGHUP};
#define COUNT(a) ((int)(sizeof(a) / sizeof((a)[0])))
static struct sigaction previous[COUNT(crash_signals)];

/* ---- async-signal-safe output ------------------------------------------------------------ */

struct line {
    char text[2048];
    size_t len;
};

static void put(struct line *l, const char *s)
{
    for (; s && *s && l->len + 1 < sizeof(l->text); s++)
        l->text[l->len++] = *s;
}

static void put_int(struct line *l, int v)
{
    char digits[16];
    int n = 0;
    unsigned u = v < 0 ? 0u - (unsigned)v : (unsigned)v;
    do
        digits[n++] = (char)('0' + u % 10);
    while ((u /= 10) && n < 15);
    if (v < 0)
        put(l, "-");
    while (n > 0 && l->len + 1 < sizeof(l->text))
        l->text[l->len++] = digits[--n];
}

static void emit(struct line *l)
{
    put(l, "\n");
    size_t off = 0;
    while (off < l->len) {
        ssize_t n = write(STDERR_FILENO, l->text + off, l->len - off);
        if (n <= 0)
            break;
        off += (size_t)n;
    }
}

static const char *signal_name(int sig)
{
    switch (sig) {
    case SIGSEGV:
        return "SIGSEGV";
    case SIGBUS:
        return "SIGBUS";
    case SIGFPE:
        return "SIGFPE";
    case SIGILL:
        return "SIGILL";
    case SIGABRT:
        return "SIGABRT";
    case SIGINT:
        return "SIGINT";
    case SIGTERM:
        return "SIGTERM";
    case SIGHUP:
        return "SIGHUP";
    }
    return "a signal";
}

/* Removes the tracked temporary files; adds "; removed X, Y" to L. */
static void remove_temps(struct line *l)
{
    bool first = true;
    for (int i = 0; i < SLOTS; i++) {
        if (!atomic_load_explicit(&temps[i].used, memory_order_acquire))
            continue;
        if (unlink(temps[i].path) == 0) {
            put(l, first ? "; removed " : ", ");
            put(l, temps[i].path);
            first = false;
        }
    }
}

/* ---- the handlers ----------------------------------------------------------------------- */

static void on_crash(int sig, siginfo_t *info, void *context)
{
    (void)info;
    (void)context;
    struct line l = {.len = 0};
    struct fatal_scope s = scope;
    if (s.library) {
        put(&l, "anvil: error: ");
        put(&l, s.library);
        put(&l, " crashed (");
        put(&l, signal_name(sig));
        put(&l, ") ");
        put(&l, s.doing ? s.doing : "with");
        put(&l, " ");
        put(&l, s.path ? s.path : "a file");
        put(&l, s.writing ? ": the file could not be written"
                          : ": the file is damaged, or of a kind the library cannot read");
        remove_temps(&l);
        emit(&l);
        _exit(s.writing ? FATAL_EXIT_WRITING : FATAL_EXIT_READING);
    }
    if (exiting) {
        put(&l, "anvil: warning: a library crashed (");
        put(&l, signal_name(sig));
        put(&l, ") while the program ended; its exit code ");
        put_int(&l, exit_code);
        put(&l, " stands");
        remove_temps(&l);
        emit(&l);
        _exit(exit_code);
    }
    /* Ours: clean up, then let the signal do what it would have done. */
    remove_temps(&l);
    if (l.len) {
        struct line m = {.len = 0};
        put(&m, "anvil: error: crashed (");
        put(&m, signal_name(sig));
        put(&m, ")");
        put(&m, l.text);
        emit(&m);
    }
    for (int i = 0; i < COUNT(crash_signals); i++) {
        if (crash_signals[i] == sig)
            sigaction(sig, &previous[i], NULL);
    }
    raise(sig); /* blocked until this handler returns; a fault also repeats on return */
}

static void on_stop(int sig)
{
    struct line l = {.len = 0};
    if (graceful && !stop_signal) {
        stop_signal = sig;
        put(&l, "anvil: interrupted (");
        put(&l, signal_name(sig));
        put(&l, "): ending as if the window were closed (again to end at once)");
        emit(&l);
        return;
    }
    put(&l, "anvil: interrupted (");
    put(&l, signal_name(sig));
    put(&l, ")");
    size_t before = l.len;
    remove_temps(&l);
    if (l.len > before)
        put(&l, " (what it was to replace is kept as it was)");
    emit(&l);
    _exit(128 + sig);
}

void fatal_install(void)
{
    static bool installed;
    if (installed)
        return;
    installed = true;
    /* An alternate stack, so that a stack overflow can be reported too. */
    static char alt[64 * 1024];
    stack_t ss = {.ss_sp = alt, .ss_size = sizeof(alt)};
    sigaltstack(&ss, NULL);
    for (int i = 0; i < COUNT(crash_signals); i++) {
        struct sigaction sa;
        memset(&sa, 0, sizeof(sa));
        sa.sa_sigaction = on_crash;
        sa.sa_flags = SA_SIGINFO | SA_ONSTACK;
        sigemptyset(&sa.sa_mask);
        sigaction(crash_signals[i], &sa, &previous[i]);
    }
    for (int i = 0; i < COUNT(stop_signals); i++) {
        struct sigaction sa, old;
        memset(&sa, 0, sizeof(sa));
        sa.sa_handler = on_stop;
        sa.sa_flags = SA_RESTART; /* a graceful stop returns: reads and waits go on */
        sigfillset(&sa.sa_mask);
        /* A signal the caller ignores (nohup, a shell's background job) stays ignored. */
        if (sigaction(stop_signals[i], NULL, &old) == 0 && old.sa_handler == SIG_IGN)
            continue;
        sigaction(stop_signals[i], &sa, NULL);
    }
}

void fatal_stop_gracefully(bool on)
{
    graceful = on;
}

int fatal_stop_requested(void)
{
    return stop_signal;
}

const char *fatal_signal_name(int sig)
{
    return signal_name(sig);
}

void fatal_enter(struct fatal_scope *saved, const char *library, const char *doing,
                 const char *path, bool writing)
{
    *saved = scope;
    struct fatal_scope s = {library, doing, path, writing};
    atomic_signal_fence(memory_order_seq_cst);
    scope = s;
    atomic_signal_fence(memory_order_seq_cst);
}

void fatal_leave(const struct fatal_scope *saved)
{
    atomic_signal_fence(memory_order_seq_cst);
    scope = *saved;
    atomic_signal_fence(memory_order_seq_cst);
}

bool fatal_track(const char *path)
{
    if (strlen(path) >= PATH_BYTES)
        return false;
    for (int i = 0; i < SLOTS; i++) {
        int expected = 0;
        if (atomic_compare_exchange_strong(&temps[i].claimed, &expected, 1)) {
            snprintf(temps[i].path, PATH_BYTES, "%s", path);
            atomic_store_explicit(&temps[i].used, 1, memory_order_release);
            return true;
        }
    }
    return false;
}

int fatal_mkstemp(char *template)
{
    /* The stop signals wait until the file is tracked: one between the two would leave it. */
    sigset_t stop, old;
    sigemptyset(&stop);
    for (int i = 0; i < COUNT(stop_signals); i++)
        sigaddset(&stop, stop_signals[i]);
    pthread_sigmask(SIG_BLOCK, &stop, &old);
    int fd = mkstemp(template);
    int saved = errno;
    if (fd >= 0)
        fatal_track(template);
    pthread_sigmask(SIG_SETMASK, &old, NULL);
    errno = saved;
    return fd;
}

void fatal_untrack(const char *path)
{
    for (int i = 0; path && i < SLOTS; i++) {
        if (atomic_load_explicit(&temps[i].used, memory_order_acquire) &&
            strcmp(temps[i].path, path) == 0) {
            atomic_store_explicit(&temps[i].used, 0, memory_order_release);
            /* The claim goes last, so no new claimant writes the path while the handler may
             * still take it as in use. */
            atomic_store(&temps[i].claimed, 0);
            return;
        }
    }
}

void fatal_exiting(int code)
{
    exit_code = code;
    exiting = 1;
}
