/*
 * common/parallel: a loop over [0, N) cut into contiguous shares, one thread each (as many as
 * there are online CPUs, at most PARALLEL_MAX), for the per-value passes of loading a step.
 * Must not know: anything above common/.
 */
#ifndef ANVIL_COMMON_PARALLEL_H
#define ANVIL_COMMON_PARALLEL_H

#include <stdbool.h>
#include <stddef.h>

#define PARALLEL_MAX 16

/* Calls FN(CTX, SHARE, BEGIN, END) for contiguous shares [BEGIN, END) covering [0, N), each
 * share at least MIN items (so little work stays on one thread), SHARE numbering them from 0;
 * the last share runs on the calling thread, and so does one whose thread cannot start.
 * Returns when all have returned: true when every call returned true. */
bool parallel_for(size_t n, size_t min, void *ctx,
                  bool (*fn)(void *ctx, int share, size_t begin, size_t end));

/* The shares parallel_for(N, MIN) makes: how many threads it runs. */
int parallel_share_count(size_t n, size_t min);

/* Names the calling thread NAME (at most 15 bytes are kept), so that `top -H`, `ps -L` and a
 * debugger tell anvil's threads apart; a name the system refuses is let go. */
void parallel_name_thread(const char *name);

#endif
