#include "common/log.h"

#include <errno.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <sys/stat.h>
#include <unistd.h>

static pthread_mutex_t log_lock = PTHREAD_MUTEX_INITIALIZER;
static enum log_level current_level = LOG_INFO;
static unsigned errors, warnings;
static char last_error[1024];
static char who[32] = "anvil"; /* the program's name in each line (log_set_name) */
static char status[256]; /* the status line on a terminal (log_status), or "" */
static int status_tty = -1; /* whether stderr is a terminal: -1 not asked yet */

void log_set_level(enum log_level level)
{
    pthread_mutex_lock(&log_lock);
    current_level = level;
    pthread_mutex_unlock(&log_lock);
}

enum log_level log_get_level(void)
{
    return current_level;
}

void log_set_name(const char *name)
{
    pthread_mutex_lock(&log_lock);
    snprintf(who, sizeof(who), "%s", name);
    pthread_mutex_unlock(&log_lock);
}

void log_msg(enum log_level level, const char *fmt, ...)
{
    char line[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof(line), fmt, ap);
    va_end(ap);

    pthread_mutex_lock(&log_lock);
    if (level == LOG_ERROR) {
        errors++;
        snprintf(last_error, sizeof(last_error), "%s", line);
    } else if (level == LOG_WARN) {
        warnings++;
    }
    if ((int)level <= (int)current_level) {
        const char *tag = level == LOG_ERROR ? "error: " : level == LOG_WARN ? "warning: " : "";
        if (status[0]) /* the message goes above the status line, which stays at the bottom */
            fprintf(stderr, "\r\033[K");
        fprintf(stderr, "%s: %s%s\n", who, tag, line);
        if (status[0])
            fprintf(stderr, "%s: %s", who, status);
    }
    pthread_mutex_unlock(&log_lock);
}

bool log_status_is_terminal(void)
{
    pthread_mutex_lock(&log_lock);
    if (status_tty < 0)
        status_tty = isatty(fileno(stderr)) && getenv("TERM") && strcmp(getenv("TERM"), "dumb");
    bool tty = status_tty;
    pthread_mutex_unlock(&log_lock);
    return tty;
}

void log_status(const char *line, bool done)
{
    bool tty = log_status_is_terminal();
    pthread_mutex_lock(&log_lock);
    if ((int)LOG_INFO <= (int)current_level) {
        if (!tty) {
            fprintf(stderr, "%s: %s\n", who, line);
        } else {
            fprintf(stderr, "\r\033[K%s: %s%s", who, line, done ? "\n" : "");
            fflush(stderr);
        }
    }
    if (tty && !done)
        snprintf(status, sizeof(status), "%s", line);
    else
        status[0] = '\0';
    pthread_mutex_unlock(&log_lock);
}

unsigned log_error_count(void)
{
    return errors;
}

unsigned log_warn_count(void)
{
    return warnings;
}

const char *log_last_error(void)
{
    return last_error;
}

char *file_read_all(const char *path, size_t *len_out)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        log_error("%s: cannot open: %s", path, strerror(errno));
        return NULL;
    }
    size_t cap = 4096, len = 0;
    char *buf = malloc(cap);
    if (!buf)
        goto error_file;
    for (;;) {
        if (len + 1 >= cap) {
            char *grown = realloc(buf, cap * 2);
            if (!grown)
                goto error_buf;
            buf = grown;
            cap *= 2;
        }
        size_t n = fread(buf + len, 1, cap - len - 1, f);
        len += n;
        if (n == 0)
            break;
    }
    if (ferror(f)) {
        log_error("%s: read failed: %s", path, strerror(errno));
        goto error_buf;
    }
    fclose(f);
    buf[len] = '\0';
    if (len_out)
        *len_out = len;
    return buf;

error_buf:
    free(buf);
error_file:
    fclose(f);
    return NULL;
}

bool file_write_atomic(const char *path, const void *data, size_t len)
{
    size_t plen = strlen(path);
    char *tmp = malloc(plen + 16);
    if (!tmp)
        return false;
    snprintf(tmp, plen + 16, "%s.tmpXXXXXX", path);
    int fd = mkstemp(tmp);
    if (fd < 0) {
        log_error("%s: cannot create a temporary file beside it: %s", path, strerror(errno));
        free(tmp);
        return false;
    }
    /* mkstemp makes the file 0600: give it what a plain create would (0666 less umask). */
    mode_t mask = umask(0);
    umask(mask);
    if (fchmod(fd, 0666 & ~mask) != 0)
        log_warn("%s: cannot set the file's permissions: %s", path, strerror(errno));
    const char *p = data;
    size_t left = len;
    while (left > 0) {
        ssize_t n = write(fd, p, left);
        if (n < 0) {
            if (errno == EINTR)
                continue;
            log_error("%s: write failed: %s", path, strerror(errno));
            goto error_tmp;
        }
        p += n;
        left -= (size_t)n;
    }
    if (fsync(fd) != 0) {
        log_error("%s: fsync failed: %s", path, strerror(errno));
        goto error_tmp;
    }
    if (close(fd) != 0) {
        fd = -1;
        log_error("%s: close failed: %s", path, strerror(errno));
        goto error_tmp;
    }
    fd = -1;
    if (rename(tmp, path) != 0) {
        log_error("%s: cannot replace: %s", path, strerror(errno));
        goto error_tmp;
    }
    free(tmp);
    return true;

error_tmp:
    if (fd >= 0)
        close(fd);
    unlink(tmp);
    free(tmp);
    return false;
}

double time_now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}
