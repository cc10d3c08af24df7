/* The display config: walls, head, navigation, hmd through the settings engine. */
#include "fuzz.h"

#include "config/display_config.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static struct display_config cfg;
    display_config_load(fuzz_file(data, size, "display.cfg"), &cfg);
    return 0;
}
