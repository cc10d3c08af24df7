/* libFuzzer harness for the DTrack parser (input/dtrack.c): any bytes, no crash, no read past
 * them, and what it accepts keeps its promises (counts in range, finite numbers). */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "input/tracker.h"

static void check_items(const struct dtrack_item *items, int n)
{
    if (n < 0 || n > DTRACK_ITEMS_MAX)
        abort();
    for (int i = 0; i < n; i++) {
        const struct dtrack_item *it = &items[i];
        if (!isfinite(it->quality) || it->button_count < 0 ||
            it->button_count > TRACKER_BUTTONS_MAX || it->axis_count < 0 ||
            it->axis_count > TRACKER_AXES_MAX)
            abort();
        for (int k = 0; k < 3; k++)
            if (!isfinite(it->position[k]))
                abort();
        for (int k = 0; k < 9; k++)
            if (!isfinite(it->rotation[k]))
                abort();
        for (int k = 0; k < it->axis_count; k++)
            if (!(fabs(it->axes[k]) <= 1.0 + 1e-6))
                abort();
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    /* An exact-size copy, so that AddressSanitizer sees any read past the end. */
    char *copy = malloc(size ? size : 1);
    if (!copy)
        return 0;
    memcpy(copy, data, size);
    static struct dtrack_frame f;
    char why[256];
    if (dtrack_parse(copy, size, &f, why, sizeof(why))) {
        check_items(f.bodies, f.body_count);
        check_items(f.flysticks, f.flystick_count);
    } else if (why[0] == '\0') {
        abort(); /* a refusal always says why */
    }
    free(copy);
    return 0;
}
