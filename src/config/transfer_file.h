/*
 * config/transfer_file: named transfer functions (optics/transfer.h) as libconfig files,
 *
 *   transfer = {
 *       name = "moist";
 *       field = "qvapor";          # qvapor | condensate | temperature | wind
 *       range = [0.0, 0.02];       # field values at x = 0 and x = 1
 *       density = 0.002;           # extinction at alpha = 1, 1/m
 *       red = ([0.0, 0.3], [1.0, 1.0]);   # control points [x, value], x ascending
 *       green = (...); blue = (...); alpha = (...);
 *   };
 *
 * Reading checks everything and fills the caller's struct only when the whole file is valid;
 * saving goes through file_write_atomic, so a failed save leaves the old file as it was.
 */
#ifndef ANVIL_CONFIG_TRANSFER_FILE_H
#define ANVIL_CONFIG_TRANSFER_FILE_H

#include <stdbool.h>
#include <stdio.h>

#include "optics/transfer.h"

/* Reads PATH into TF.  On failure logs one message "FILE:LINE: SETTING: expected ..." (or
 * "FILE: reason") and returns false with TF untouched. */
bool transfer_file_load(const char *path, struct transfer_function *tf);

/* Writes TF to PATH atomically.  Returns false (logged) on failure; the old file is kept. */
bool transfer_file_save(const char *path, const struct transfer_function *tf);

/* Writes TF as the group "INDENT NAME = { ... };" of a file (what save writes under NAME
 * "transfer"), every line after INDENT; numbers that read back to the same bits. */
void transfer_file_write_group(FILE *f, const char *name, const struct transfer_function *tf,
                               const char *indent);

#endif
