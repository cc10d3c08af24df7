/* config internal: a transfer function's group read for the settings engine (look.transfer
 * written in place in a scene file) as transfer_file_load reads a file's.  Nothing outside
 * src/config/ includes it. */
#ifndef ANVIL_CONFIG_TRANSFER_GROUP_H
#define ANVIL_CONFIG_TRANSFER_GROUP_H

#include <stdbool.h>

#include <libconfig.h>

#include "optics/transfer.h"

/* Where messages point: "FILE:LINE: PREFIX.SETTING: expected ...", LINE the parsed text's line
 * mapped through LOCATE (NULL: FILE and that line). */
struct transfer_where {
    const char *file;
    const char *prefix; /* "transfer", "look.transfer" */
    void (*locate)(void *user, int line, const char **file, int *file_line);
    void *user;
};

/* Reads the group G (name, field, range, density, red, green, blue, alpha) into OUT, checked
 * as transfer_file_load checks a file; OUT is untouched on failure (logged once). */
bool transfer_group_read(const config_setting_t *g, const struct transfer_where *w,
                         struct transfer_function *out);

#endif
