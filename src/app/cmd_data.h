/*
 * app/cmd_data: the data commands (`anvil info`, `anvil synth`, `anvil convert`).  Each takes
 * argv with argv[0] the command name and returns the program's exit code (app/app.h).
 */
#ifndef ANVIL_APP_CMD_DATA_H
#define ANVIL_APP_CMD_DATA_H

int cmd_info(int argc, char **argv);
int cmd_synth(int argc, char **argv);
int cmd_convert(int argc, char **argv);

#endif
