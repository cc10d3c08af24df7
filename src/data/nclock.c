#include "data/nclock.h"

#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <netcdf.h>

#include "common/fatal.h"
#include "common/log.h"

static pthread_once_t once = PTHREAD_ONCE_INIT;
static pthread_mutex_t lock;

static void init_lock(void)
{
    pthread_mutexattr_t attr;
    pthread_mutexattr_init(&attr);
    pthread_mutexattr_settype(&attr, PTHREAD_MUTEX_RECURSIVE);
    pthread_mutex_init(&lock, &attr);
    pthread_mutexattr_destroy(&attr);
}

/* The lock's recursion, and at each level whether it entered a fatal scope (guarded by the
 * lock itself). */
#define DEPTH_MAX 32
static int depth;
static bool scoped[DEPTH_MAX];
static struct fatal_scope saved[DEPTH_MAX];

void data_nc_lock(void)
{
    pthread_once(&once, init_lock);
    pthread_mutex_lock(&lock);
    if (depth < DEPTH_MAX)
        scoped[depth] = false;
    depth++;
}

void data_nc_lock_file(const char *path, const char *doing, bool writing)
{
    data_nc_lock();
    if (depth <= DEPTH_MAX) {
        fatal_enter(&saved[depth - 1], DATA_NC_LIBRARY, doing, path, writing);
        scoped[depth - 1] = true;
    }
}

void data_nc_unlock(void)
{
    depth--;
    if (depth < DEPTH_MAX && scoped[depth])
        fatal_leave(&saved[depth]);
    pthread_mutex_unlock(&lock);
}

bool data_nc_create_beside(const char *path, int cmode, char **tmp, int *ncid)
{
    *ncid = -1;
    *tmp = NULL;
    char target[4096];
    unsigned mode;
    if (!file_write_target(path, target, sizeof(target), &mode))
        return false;
    size_t len = strlen(target) + 32;
    *tmp = malloc(len);
    if (!*tmp) {
        log_error("%s: out of memory", path);
        return false;
    }
    /* A name no other writer can take: mkstemp reserves it, nc_create then clobbers it. */
    snprintf(*tmp, len, "%s.tmpXXXXXX", target);
    int fd = fatal_mkstemp(*tmp); /* removed if a signal ends the process before the rename */
    if (fd < 0) {
        log_error("%s: cannot create a temporary file beside it: %s", path, strerror(errno));
        free(*tmp);
        *tmp = NULL;
        return false;
    }
    close(fd);
    data_nc_lock_file(path, "writing", true);
    int st = nc_create(*tmp, cmode, ncid);
    data_nc_unlock();
    if (st != NC_NOERR) {
        *ncid = -1;
        log_error("%s: cannot create: %s", *tmp, nc_strerror(st));
        return false;
    }
    return true;
}

bool data_nc_finish_beside(const char *path, char **tmp, int *ncid, bool ok, int steps)
{
    if (ok && steps == 0) {
        log_error("%s: no time steps to write", path);
        ok = false;
    }
    data_nc_lock_file(path, "writing", true);
    int st = *ncid >= 0 ? nc_close(*ncid) : NC_NOERR;
    data_nc_unlock();
    *ncid = -1;
    if (ok && st != NC_NOERR) {
        log_error("%s: cannot finish writing: %s", *tmp, nc_strerror(st));
        ok = false;
    }
    char target[4096];
    unsigned mode = 0644;
    if (ok)
        ok = file_write_target(path, target, sizeof(target), &mode);
    if (ok) {
        /* On disk before it replaces the old file. */
        int fd = open(*tmp, O_RDONLY);
        if (fd < 0 || fsync(fd) != 0) {
            log_error("%s: cannot flush to disk: %s", *tmp, strerror(errno));
            ok = false;
        }
        if (fd >= 0)
            close(fd);
        chmod(*tmp, (mode_t)mode);
    }
    if (ok && rename(*tmp, target) != 0) {
        log_error("%s: cannot move %s into place: %s", path, *tmp, strerror(errno));
        ok = false;
    }
    if (ok) {
        fatal_untrack(*tmp);
        free(*tmp);
        *tmp = NULL;
    }
    return ok;
}

void data_nc_abandon(char **tmp, int *ncid)
{
    if (*ncid >= 0) {
        data_nc_lock_file(*tmp ? *tmp : "a NetCDF file", "writing", true);
        nc_close(*ncid);
        data_nc_unlock();
        *ncid = -1;
    }
    if (*tmp) {
        remove(*tmp);
        fatal_untrack(*tmp);
        free(*tmp);
        *tmp = NULL;
    }
}
