/* Scripted input (docs/menu.md) and head path files: line-based parsers of numbers and
 * names. */
#include "fuzz.h"

#include "display/display.h"
#include "input/input.h"

static bool known(const char *name, void *user)
{
    (void)user;
    return strcmp(name, "time.play") == 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fuzz_file(data, size, "script.txt");
    struct input_source *s = input_script_open(path);
    if (s) {
        input_script_check_aims(s, known, NULL);
        struct input_queue q;
        input_queue_clear(&q);
        long last = input_script_last_frame(s);
        for (long f = 0; f <= last && f < 4096; f++) {
            input_queue_clear(&q);
            input_source_poll(s, &(struct input_frame){.frame = f}, &q);
        }
        input_source_destroy(s);
    }
    struct display_path p;
    if (display_path_load(path, &p)) {
        struct display_pose pose;
        display_path_eval(&p, 0.5, &pose);
        display_path_finish(&p);
    }
    return 0;
}
