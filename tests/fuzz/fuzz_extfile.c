/* Extinction files (data.format = "extinction") in classic NetCDF: layout, axes, steps. */
#include "fuzz.h"

#include "data/extfile.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (!fuzz_is_classic(data, size))
        return 0;
    const char *path = fuzz_file(data, size, "ext.nc");
    if (!extfile_probe(path))
        return 0;
    struct extfile *f = extfile_open(path, 256.0);
    if (!f)
        return 0;
    for (int s = 0; s < extfile_step_count(f) && s < 4; s++) {
        struct ext_volume v;
        if (extfile_read_step(f, s, &v, NULL))
            ext_volume_finish(&v);
    }
    extfile_close(f);
    return 0;
}
