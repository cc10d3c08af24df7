/*
 * fake_tracker: the other end of anvil's tracker links for the command-line tests, on
 * 127.0.0.1 only.
 *
 *   fake_tracker port                           prints a free UDP port
 *   fake_tracker dtrack PORT FILE [RATE [SECONDS]]
 *       sends FILE's datagrams (separated by lines "---") to 127.0.0.1:PORT, cycling, RATE per
 *       second (60) for SECONDS (10), each after an "fr N" line of its own
 *   fake_tracker vrpn PORTFILE FILE [RATE [SECONDS]]
 *       listens on a free port (written to PORTFILE), and to each client in turn sends the
 *       cookie, the descriptions of FILE's devices and types, then FILE's frames (separated by
 *       "---") cycling, RATE per second, for SECONDS in all.  FILE's lines:
 *         pose DEVICE SENSOR X Y Z QX QY QZ QW
 *         button DEVICE BUTTON STATE
 *         analog DEVICE VALUE...
 */
#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "fake_tracker.h"

#include "common/log.h"
#include "input/tracker.h"

#define FRAMES_MAX 256
#define DEVICES_MAX 8

static char *frames[FRAMES_MAX];
static int frame_count;

/* Splits TEXT into frames at lines "---". */
static void split(char *text)
{
    char *start = text;
    for (char *line = text; line && *line;) {
        char *next = strchr(line, '\n');
        if (strncmp(line, "---", 3) == 0) {
            *line = '\0';
            if (frame_count < FRAMES_MAX)
                frames[frame_count++] = start;
            start = next ? next + 1 : line + strlen(line);
        }
        line = next ? next + 1 : NULL;
    }
    if (*start && frame_count < FRAMES_MAX)
        frames[frame_count++] = start;
}

static int dtrack(int port, double rate, double seconds)
{
    int fd = fake_udp_socket();
    double start = time_now_ms();
    for (long n = 0; (time_now_ms() - start) < seconds * 1000.0; n++) {
        char buf[8192];
        snprintf(buf, sizeof(buf), "fr %ld\r\n%s", n, frames[n % frame_count]);
        fake_udp_send_text(fd, port, buf);
        fake_sleep_ms((int)(1000.0 / rate));
    }
    close(fd);
    return 0;
}

static char devices[DEVICES_MAX][TRACKER_NAME_MAX];
static int device_count;

static int device_id(const char *name)
{
    for (int i = 0; i < device_count; i++) {
        if (strcmp(devices[i], name) == 0)
            return i;
    }
    if (device_count == DEVICES_MAX)
        return 0;
    snprintf(devices[device_count], sizeof(devices[0]), "%s", name);
    return device_count++;
}

/* One frame's messages into B. */
static void vrpn_frame(struct fake_bytes *b, char *text)
{
    char *save = NULL;
    for (char *line = strtok_r(text, "\n", &save); line; line = strtok_r(NULL, "\n", &save)) {
        char dev[TRACKER_NAME_MAX];
        int sensor, button, state, used = 0;
        double v[16];
        if (sscanf(line, "pose %63s %d %lf %lf %lf %lf %lf %lf %lf", dev, &sensor, &v[0], &v[1],
                   &v[2], &v[3], &v[4], &v[5], &v[6]) == 9) {
            fake_vrpn_pose(b, device_id(dev), 0, sensor, v, v + 3);
        } else if (sscanf(line, "button %63s %d %d", dev, &button, &state) == 3) {
            fake_vrpn_button(b, device_id(dev), 1, button, state);
        } else if (sscanf(line, "analog %63s %n", dev, &used) == 1 && used > 0) {
            int n = 0;
            char *p = line + used, *end;
            while (n < 16 && (v[n] = strtod(p, &end), end != p)) {
                n++;
                p = end;
            }
            fake_vrpn_analog(b, device_id(dev), 2, v, n);
        }
    }
}

static int vrpn(const char *port_file, double rate, double seconds)
{
    /* The devices, in order of appearance, from a first pass over a copy. */
    for (int f = 0; f < frame_count; f++) {
        char copy[8192];
        snprintf(copy, sizeof(copy), "%s", frames[f]);
        char *save = NULL;
        for (char *line = strtok_r(copy, "\n", &save); line; line = strtok_r(NULL, "\n", &save)) {
            char kind[16], dev[TRACKER_NAME_MAX];
            if (sscanf(line, "%15s %63s", kind, dev) == 2)
                device_id(dev);
        }
    }
    int port = 0;
    int lfd = fake_tcp_listen(&port);
    if (lfd < 0) {
        perror("listen");
        return 1;
    }
    FILE *pf = fopen(port_file, "w");
    if (!pf) {
        perror(port_file);
        return 1;
    }
    fprintf(pf, "%d\n", port);
    fclose(pf);
    double start = time_now_ms();
    static struct fake_bytes b;
    while ((time_now_ms() - start) < seconds * 1000.0) {
        int fd = fake_vrpn_accept(lfd, 0.1);
        if (fd < 0)
            continue;
        b.n = 0;
        for (int i = 0; i < device_count; i++)
            fake_vrpn_describe(&b, VRPN_SENDER_DESCRIPTION, i, devices[i]);
        fake_vrpn_describe(&b, VRPN_TYPE_DESCRIPTION, 0, "vrpn_Tracker Pos_Quat");
        fake_vrpn_describe(&b, VRPN_TYPE_DESCRIPTION, 1, "vrpn_Button Change");
        fake_vrpn_describe(&b, VRPN_TYPE_DESCRIPTION, 2, "vrpn_Analog Channel");
        bool ok = fake_write_chunks(fd, b.data, b.n, 0);
        for (long n = 0; ok && (time_now_ms() - start) < seconds * 1000.0; n++) {
            char copy[8192];
            snprintf(copy, sizeof(copy), "%s", frames[n % frame_count]);
            b.n = 0;
            vrpn_frame(&b, copy);
            ok = fake_write_chunks(fd, b.data, b.n, 0);
            fake_sleep_ms((int)(1000.0 / rate));
        }
        close(fd);
    }
    close(lfd);
    return 0;
}

int main(int argc, char **argv)
{
    if (argc == 2 && strcmp(argv[1], "port") == 0) {
        int fd = fake_udp_socket();
        struct sockaddr_in a = {.sin_family = AF_INET};
        a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        socklen_t len = sizeof(a);
        if (bind(fd, (struct sockaddr *)&a, sizeof(a)) != 0 ||
            getsockname(fd, (struct sockaddr *)&a, &len) != 0)
            return 1;
        printf("%d\n", ntohs(a.sin_port));
        close(fd);
        return 0;
    }
    if (argc < 4 || (strcmp(argv[1], "dtrack") != 0 && strcmp(argv[1], "vrpn") != 0)) {
        fprintf(stderr, "usage: fake_tracker port | dtrack PORT FILE [RATE [SECONDS]] | "
                        "vrpn PORTFILE FILE [RATE [SECONDS]]\n");
        return 2;
    }
    log_set_level(LOG_ERROR);
    char *text = file_read_all(argv[3], NULL);
    if (!text)
        return 1;
    split(text);
    if (frame_count == 0) {
        fprintf(stderr, "%s: no frames\n", argv[3]);
        return 1;
    }
    double rate = argc > 4 ? atof(argv[4]) : 60.0, seconds = argc > 5 ? atof(argv[5]) : 10.0;
    if (!(rate > 0.0))
        rate = 60.0;
    int rc = strcmp(argv[1], "dtrack") == 0 ? dtrack(atoi(argv[2]), rate, seconds)
                                            : vrpn(argv[2], rate, seconds);
    free(text);
    return rc;
}
