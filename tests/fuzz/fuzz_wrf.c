/* WRF output in classic NetCDF: the header check, opening (grid, variables, Times, metadata,
 * the model top) and reading every step (heights, resampling, bad values, wind, temperature)
 * within a budget. */
#include "fuzz.h"

#include "data/wrf.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (!fuzz_is_classic(data, size))
        return 0;
    const char *path = fuzz_file(data, size, "wrfout.nc");
    struct wrf *w = wrf_open(&path, 1, 256.0);
    if (!w)
        return 0;
    struct wrf_desc d;
    wrf_desc_defaults(&d);
    d.memory_mb = 256.0;
    d.qvapor = d.temperature = d.wind = true;
    for (int s = 0; s < wrf_step_count(w) && s < 4; s++) {
        struct field_volume v;
        if (wrf_read_step(w, s, &d, &v, NULL))
            field_volume_finish(&v);
    }
    wrf_close(w);
    return 0;
}
