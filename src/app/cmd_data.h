/*
 * app/cmd_data: the data commands (`anvil info`, `anvil synth`, `anvil convert`) and the
 * mapping from the config's data.* and optics settings to the data part's descriptions.
 * Each command takes argv with argv[0] the command name and returns the program's exit code
 * (0 done, 1 bad input, 2 usage, 4 other failure: app/app.h).
 */
#ifndef ANVIL_APP_CMD_DATA_H
#define ANVIL_APP_CMD_DATA_H

#include "config/config.h"
#include "data/source.h"

int cmd_info(int argc, char **argv);
int cmd_synth(int argc, char **argv);
int cmd_convert(int argc, char **argv);

/* Fills OUT from CFG: format, files (pointers into CFG, which must outlive OUT), WRF reading
 * (data.levels, data.top, data.stride, data.crop, data.memory), Isabel sizes, optics, the
 * species toggles, procedural detail and the height exaggeration. */
void cmd_data_source_desc(const struct config *cfg, const char **file_ptrs,
                          struct data_source_desc *out);

/* The procedural detail CFG asks for (effects.detail, detail.*). */
void cmd_data_detail_desc(const struct config *cfg, struct detail_desc *out);

#endif
