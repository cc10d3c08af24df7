/* The scene config: the settings engine over libconfig, @include and --set. */
#include "fuzz.h"

#include "config/config.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static struct config cfg;
    const char *path = fuzz_file(data, size, "scene.cfg");
    if (config_load(path, &cfg))
        config_validate(&cfg);
    return 0;
}
