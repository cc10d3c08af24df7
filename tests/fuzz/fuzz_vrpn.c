/* libFuzzer harness for the VRPN parser (input/vrpn.c): any byte stream, no crash, every byte
 * consumed, and the same events whether the stream comes whole or in chunks (the first byte
 * chooses the chunk size): messages split across reads are read as if they came at once. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "input/tracker.h"

#define EVENTS_MAX 4096

struct seen {
    int count;
    uint8_t type[EVENTS_MAX];
    int32_t a[EVENTS_MAX], b[EVENTS_MAX];
};

static void parse(const uint8_t *data, size_t size, size_t chunk, struct seen *s)
{
    static struct vrpn_parser p;
    vrpn_parser_init(&p);
    s->count = 0;
    struct vrpn_event ev;
    for (size_t at = 0; at < size;) {
        size_t len = size - at < chunk ? size - at : chunk;
        /* An exact-size copy per read, as recv would give it. */
        uint8_t *piece = malloc(len);
        if (!piece)
            abort();
        memcpy(piece, data + at, len);
        size_t pos = 0;
        enum vrpn_event_type t;
        while ((t = vrpn_parse(&p, piece, len, &pos, &ev)) != VRPN_NONE) {
            if (t != ev.type || pos > len)
                abort();
            if (s->count < EVENTS_MAX) {
                s->type[s->count] = (uint8_t)t;
                s->a[s->count] = t == VRPN_POSE     ? ev.sensor
                                 : t == VRPN_BUTTON ? ev.button
                                                    : ev.count;
                s->b[s->count] = ev.sender_id;
                s->count++;
            }
        }
        if (pos != len)
            abort();
        free(piece);
        at += len;
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1)
        return 0;
    size_t chunk = 1 + data[0] % 64;
    static struct seen whole, split;
    parse(data + 1, size - 1, size, &whole);
    parse(data + 1, size - 1, chunk, &split);
    if (whole.count != split.count || memcmp(whole.type, split.type, (size_t)whole.count) != 0 ||
        memcmp(whole.a, split.a, sizeof(int32_t) * (size_t)whole.count) != 0 ||
        memcmp(whole.b, split.b, sizeof(int32_t) * (size_t)whole.count) != 0)
        abort();
    return 0;
}
