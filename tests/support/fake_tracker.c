#include "fake_tracker.h"

#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include "common/log.h"
#include "input/tracker.h"

static struct sockaddr_in loopback(int port)
{
    struct sockaddr_in a = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)};
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    return a;
}

int fake_udp_socket(void)
{
    return socket(AF_INET, SOCK_DGRAM, 0);
}

bool fake_udp_send(int fd, int port, const void *data, size_t len)
{
    struct sockaddr_in a = loopback(port);
    return sendto(fd, data, len, 0, (struct sockaddr *)&a, sizeof(a)) == (ssize_t)len;
}

bool fake_udp_send_text(int fd, int port, const char *text)
{
    return fake_udp_send(fd, port, text, strlen(text));
}

int fake_tcp_listen(int *port)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    if (fd < 0)
        return -1;
    int one = 1;
    setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
    struct sockaddr_in a = loopback(*port);
    socklen_t len = sizeof(a);
    if (bind(fd, (struct sockaddr *)&a, sizeof(a)) != 0 || listen(fd, 4) != 0 ||
        getsockname(fd, (struct sockaddr *)&a, &len) != 0) {
        close(fd);
        return -1;
    }
    *port = ntohs(a.sin_port);
    return fd;
}

int fake_tcp_accept(int listen_fd, double timeout_s)
{
    struct pollfd p = {.fd = listen_fd, .events = POLLIN};
    if (poll(&p, 1, (int)(timeout_s * 1000)) <= 0)
        return -1;
    return accept(listen_fd, NULL, NULL);
}

bool fake_read_exact(int fd, void *buf, size_t n, double timeout_s)
{
    double end = time_now_ms() + timeout_s * 1000.0;
    uint8_t *b = buf;
    while (n > 0) {
        int left = (int)(end - time_now_ms());
        struct pollfd p = {.fd = fd, .events = POLLIN};
        if (left <= 0 || poll(&p, 1, left) <= 0)
            return false;
        ssize_t r = recv(fd, b, n, 0);
        if (r <= 0)
            return false;
        b += r;
        n -= (size_t)r;
    }
    return true;
}

bool fake_write_chunks(int fd, const void *buf, size_t n, size_t chunk)
{
    const uint8_t *b = buf;
    while (n > 0) {
        size_t k = chunk && chunk < n ? chunk : n;
        ssize_t w = send(fd, b, k, MSG_NOSIGNAL);
        if (w <= 0)
            return false;
        b += w;
        n -= (size_t)w;
        if (chunk)
            fake_sleep_ms(0);
    }
    return true;
}

int fake_vrpn_accept(int listen_fd, double timeout_s)
{
    int fd = fake_tcp_accept(listen_fd, timeout_s);
    if (fd < 0)
        return -1;
    uint8_t cookie[VRPN_COOKIE_BYTES];
    if (!fake_read_exact(fd, cookie, sizeof(cookie), timeout_s) ||
        memcmp(cookie, "vrpn: ver. 07.", 14) != 0) {
        close(fd);
        return -1;
    }
    uint8_t mine[VRPN_COOKIE_BYTES];
    vrpn_write_cookie(mine, sizeof(mine));
    if (!fake_write_chunks(fd, mine, sizeof(mine), 0)) {
        close(fd);
        return -1;
    }
    return fd;
}

void fake_vrpn_describe(struct fake_bytes *b, int32_t kind, int32_t id, const char *name)
{
    b->n += vrpn_write_description(b->data + b->n, sizeof(b->data) - b->n, kind, id, name, 0);
}

void fake_vrpn_pose(struct fake_bytes *b, int32_t sender, int32_t type, int32_t sensor,
                    const double position[3], const double quat[4])
{
    b->n += vrpn_write_pose(b->data + b->n, sizeof(b->data) - b->n, sender, type, 1.0, sensor,
                            position, quat);
}

void fake_vrpn_button(struct fake_bytes *b, int32_t sender, int32_t type, int32_t button,
                      int32_t state)
{
    b->n +=
        vrpn_write_button(b->data + b->n, sizeof(b->data) - b->n, sender, type, 1.0, button, state);
}

void fake_vrpn_analog(struct fake_bytes *b, int32_t sender, int32_t type, const double *v, int n)
{
    b->n += vrpn_write_analog(b->data + b->n, sizeof(b->data) - b->n, sender, type, 1.0, v, n);
}

void fake_sleep_ms(int ms)
{
    struct timespec t = {.tv_sec = ms / 1000, .tv_nsec = (long)(ms % 1000) * 1000000L};
    nanosleep(&t, NULL);
}

bool fake_wait(bool (*done)(void *user), void *user, double timeout_s)
{
    double end = time_now_ms() + timeout_s * 1000.0;
    while (!done(user)) {
        if (time_now_ms() > end)
            return false;
        fake_sleep_ms(1);
    }
    return true;
}
