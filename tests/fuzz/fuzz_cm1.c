/* CM1 output in classic NetCDF: the header check, opening (coordinates, levels,
 * variables and their units, times) and reading every step (resampling, bad values,
 * temperature, density, wind) within a budget. */
#include "fuzz.h"

#include "data/cm1.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (!fuzz_is_classic(data, size))
        return 0;
    const char *path = fuzz_file(data, size, "cm1.nc");
    cm1_probe(path);
    struct hgrid *h = cm1_open(&path, 1, 256.0);
    if (!h)
        return 0;
    struct hgrid_desc d = {.memory_mb = 256.0, .qvapor = true, .temperature = true, .wind = true};
    for (int s = 0; s < hgrid_step_count(h) && s < 4; s++) {
        struct field_volume v;
        d.native_levels = s % 2 == 0; /* the file's own levels, and the even ones */
        if (hgrid_read_step(h, s, &d, &v, NULL))
            field_volume_finish(&v);
    }
    hgrid_close(h);
    return 0;
}
