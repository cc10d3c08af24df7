/* Options the commands share (app.h): numbers, and where each --set goes. */
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "app/app.h"
#include "common/log.h"

bool app_option_long(const char *command, const char *option, const char *s, long lo, long hi,
                     long *out)
{
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (errno || end == s || *end || v < lo || v > hi) {
        log_error("%s: %s: expected an integer in [%ld, %ld], got \"%s\"", command, option, lo, hi,
                  s);
        return false;
    }
    *out = v;
    return true;
}

bool app_option_double(const char *command, const char *option, const char *s, double lo, double hi,
                       double *out)
{
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (errno || end == s || *end || !(v >= lo && v <= hi)) {
        log_error("%s: %s: expected a number in [%g, %g], got \"%s\"", command, option, lo, hi, s);
        return false;
    }
    *out = v;
    return true;
}

bool app_route_sets(char **sets, int *n_sets, bool have_display, char **display_sets,
                    int *n_display_sets)
{
    int kept = 0;
    *n_display_sets = 0;
    for (int i = 0; i < *n_sets; i++) {
        if (!display_config_has_setting(sets[i])) {
            sets[kept++] = sets[i];
        } else if (have_display) {
            display_sets[(*n_display_sets)++] = sets[i];
        } else {
            const char *path = sets[i] + strspn(sets[i], " \t");
            log_error("%.*s is a display setting: it needs --display FILE",
                      (int)strcspn(path, "= \t"), path);
            return false;
        }
    }
    *n_sets = kept;
    return true;
}

bool app_load_display_config(const char *path, char *const *sets, int n_sets,
                             struct display_config *cfg)
{
    if (!display_config_load(path, cfg))
        return false;
    for (int i = 0; i < n_sets; i++) {
        if (!display_config_set(cfg, sets[i]))
            return false;
    }
    return display_config_validate(cfg);
}
