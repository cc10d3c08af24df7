/* Transfer function files (the menu's saves). */
#include "fuzz.h"

#include "config/transfer_file.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    struct transfer_function tf;
    if (transfer_file_load(fuzz_file(data, size, "tf.cfg"), &tf)) {
        for (int c = 0; c < TRANSFER_CHANNELS; c++)
            transfer_eval(&tf, (enum transfer_channel)c, 0.5f);
    }
    return 0;
}
