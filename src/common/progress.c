/* Progress lines: rewritten in place on a terminal, plain and sparse elsewhere. */
#include "common/progress.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"

#define QUIET_MS 1000.0    /* nothing is said in a job's first second */
#define TTY_EVERY_MS 200.0 /* the terminal line is rewritten at most 5 times a second */
#define LINE_EVERY_MS 5000.0

static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;

void progress_begin(struct progress *p, const char *what, const char *unit, uint64_t total)
{
    memset(p, 0, sizeof(*p));
    snprintf(p->what, sizeof(p->what), "%s", what);
    snprintf(p->unit, sizeof(p->unit), "%s", unit);
    p->total = total;
    p->start_ms = p->last_ms = time_now_ms();
    const char *quiet = getenv("ANVIL_PROGRESS_QUIET_MS"); /* tests: show short jobs too */
    p->quiet_ms = quiet ? atof(quiet) : QUIET_MS;
}

static void clock_text(double s, char *buf, size_t size)
{
    long t = (long)(s + 0.5);
    if (t >= 3600)
        snprintf(buf, size, "%ld:%02ld:%02ld", t / 3600, t / 60 % 60, t % 60);
    else
        snprintf(buf, size, "%ld:%02ld", t / 60, t % 60);
}

void progress_format(const struct progress *p, uint64_t done, double elapsed_s, char *buf,
                     int size)
{
    char gone[32], left[64] = "";
    clock_text(elapsed_s, gone, sizeof(gone));
    if (done > 0 && done < p->total) {
        char t[24];
        clock_text(elapsed_s * (double)(p->total - done) / (double)done, t, sizeof(t));
        snprintf(left, sizeof(left), ", about %s to go", t);
    }
    snprintf(buf, (size_t)size, "%s: %s %llu of %llu (%.0f %%), %s gone%s", p->what, p->unit,
             (unsigned long long)done, (unsigned long long)p->total,
             p->total ? 100.0 * (double)done / (double)p->total : 100.0, gone, left);
}

void progress_update(struct progress *p, uint64_t done)
{
    pthread_mutex_lock(&lock);
    if (done > p->done)
        p->done = done;
    double now = time_now_ms();
    bool tty = log_status_is_terminal();
    double every = tty ? TTY_EVERY_MS : LINE_EVERY_MS;
    bool due = now - p->start_ms >= p->quiet_ms && (now - p->last_ms >= every || !p->shown);
    if (due && p->done < p->total) {
        char line[200];
        progress_format(p, p->done, (now - p->start_ms) * 1e-3, line, sizeof(line));
        log_status(line, false);
        p->shown = true;
        p->last_ms = now;
    }
    pthread_mutex_unlock(&lock);
}

void progress_end(struct progress *p)
{
    pthread_mutex_lock(&lock);
    if (p->shown) {
        char line[200];
        progress_format(p, p->done, (time_now_ms() - p->start_ms) * 1e-3, line, sizeof(line));
        log_status(line, true);
        p->shown = false;
    }
    pthread_mutex_unlock(&lock);
}
