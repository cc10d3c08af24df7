/* GSHHG binned shoreline files (classic NetCDF): the bin layout and the segment and point
 * indices. */
#include "fuzz.h"

#include "data/coast.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (!fuzz_is_classic(data, size))
        return 0;
    const char *path = fuzz_file(data, size, "binned.nc");
    static const double boxes[2][4] = {{-90, 90, -180, 180}, {20, 30, -95, -85}};
    for (int b = 0; b < 2; b++) {
        struct coast_lines c;
        if (coast_read(path, boxes[b], COAST_POND, &c))
            coast_lines_finish(&c);
    }
    return 0;
}
