/*
 * common/progress: how far a long job is.  A job of TOTAL units (frames, tiles, steps) reports
 * each unit done; on a terminal one status line is rewritten in place ("render: frame 12 of 34
 * (35 %), 0:12 gone, about 0:22 to go"), elsewhere a plain line at most every few seconds and
 * at the end; nothing with --quiet (the log level below info).  Jobs under a second say
 * nothing at all.  Thread safe for one job updated from several threads.
 */
#ifndef ANVIL_COMMON_PROGRESS_H
#define ANVIL_COMMON_PROGRESS_H

#include <stdbool.h>
#include <stdint.h>

struct progress {
    char what[48]; /* "render", "reference" */
    char unit[16]; /* "frame", "row", "step" */
    uint64_t total, done;
    double start_ms, last_ms;
    double quiet_ms; /* nothing before this: 1 s, or $ANVIL_PROGRESS_QUIET_MS (tests) */
    bool shown;
};

void progress_begin(struct progress *p, const char *what, const char *unit, uint64_t total);
/* DONE units of TOTAL are finished. */
void progress_update(struct progress *p, uint64_t done);
/* The job ended (or failed): the terminal line is closed with the time it took. */
void progress_end(struct progress *p);

/* The status text for DONE of TOTAL after ELAPSED_S seconds, for tests. */
void progress_format(const struct progress *p, uint64_t done, double elapsed_s, char *buf,
                     int size);

#endif
