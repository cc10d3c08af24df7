#define _GNU_SOURCE /* pthread_setname_np */
#include "common/parallel.h"

#include <pthread.h>
#include <stdio.h>
#include <unistd.h>

struct share {
    void *ctx;
    bool (*fn)(void *ctx, int share, size_t begin, size_t end);
    int index;
    size_t begin, end;
    bool ok;
    pthread_t thread;
};

static void *run_share(void *arg)
{
    struct share *s = arg;
    s->ok = s->begin >= s->end || s->fn(s->ctx, s->index, s->begin, s->end);
    return NULL;
}

static void *start_share(void *arg)
{
    parallel_name_thread("anvil-share");
    return run_share(arg);
}

int parallel_share_count(size_t n, size_t min)
{
    long cpus = sysconf(_SC_NPROCESSORS_ONLN);
    int tn = cpus < 1 ? 1 : cpus > PARALLEL_MAX ? PARALLEL_MAX : (int)cpus;
    if (min < 1)
        min = 1;
    if ((size_t)tn > n / min + 1)
        tn = (int)(n / min + 1);
    return tn;
}

bool parallel_for(size_t n, size_t min, void *ctx,
                  bool (*fn)(void *ctx, int share, size_t begin, size_t end))
{
    int tn = parallel_share_count(n, min);
    size_t per = (n + (size_t)tn - 1) / (size_t)tn;
    struct share jobs[PARALLEL_MAX];
    bool started[PARALLEL_MAX] = {false};
    for (int t = 0; t < tn; t++) {
        size_t begin = per * (size_t)t < n ? per * (size_t)t : n;
        size_t end = begin + per < n ? begin + per : n;
        jobs[t] = (struct share){.ctx = ctx, .fn = fn, .index = t, .begin = begin, .end = end};
        if (t == tn - 1 || pthread_create(&jobs[t].thread, NULL, start_share, &jobs[t]) != 0)
            run_share(&jobs[t]);
        else
            started[t] = true;
    }
    bool ok = true;
    for (int t = 0; t < tn; t++) {
        if (started[t])
            pthread_join(jobs[t].thread, NULL);
        ok = ok && jobs[t].ok;
    }
    return ok;
}

void parallel_name_thread(const char *name)
{
    char kept[16];
    snprintf(kept, sizeof(kept), "%s", name);
    (void)pthread_setname_np(pthread_self(), kept);
}
