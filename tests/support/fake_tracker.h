/*
 * Test support: the other end of a tracker link on loopback (127.0.0.1 only).  A DTrack sender
 * is a UDP socket; a fake VRPN server is a listening TCP socket the test accepts on and then
 * writes VRPN bytes to (built with input/tracker.h's writers) while anvil's client thread
 * reads them.  Every wait has a timeout, so a broken client fails a test instead of hanging
 * it.
 */
#ifndef ANVIL_FAKE_TRACKER_H
#define ANVIL_FAKE_TRACKER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* A UDP socket to send DTrack datagrams from. */
int fake_udp_socket(void);
/* Sends TEXT (its bytes, no NUL) to 127.0.0.1:PORT. */
bool fake_udp_send(int fd, int port, const void *data, size_t len);
bool fake_udp_send_text(int fd, int port, const char *text);

/* A TCP socket listening on 127.0.0.1 at a free port (*PORT). */
int fake_tcp_listen(int *port);
/* The next connection, or -1 after TIMEOUT_S seconds. */
int fake_tcp_accept(int listen_fd, double timeout_s);
/* Reads exactly N bytes within TIMEOUT_S; false on timeout or end of stream. */
bool fake_read_exact(int fd, void *buf, size_t n, double timeout_s);
/* Writes N bytes in chunks of CHUNK (0: at once), so a reader sees them split. */
bool fake_write_chunks(int fd, const void *buf, size_t n, size_t chunk);

/* VRPN server side: accepts a client within TIMEOUT_S, reads its cookie (checking the
 * version) and sends the server's.  The connection, or -1. */
int fake_vrpn_accept(int listen_fd, double timeout_s);

/* A growing byte buffer of VRPN messages. */
struct fake_bytes {
    uint8_t data[65536];
    size_t n;
};

void fake_vrpn_describe(struct fake_bytes *b, int32_t kind, int32_t id, const char *name);
void fake_vrpn_pose(struct fake_bytes *b, int32_t sender, int32_t type, int32_t sensor,
                    const double position[3], const double quat[4]);
void fake_vrpn_button(struct fake_bytes *b, int32_t sender, int32_t type, int32_t button,
                      int32_t state);
void fake_vrpn_analog(struct fake_bytes *b, int32_t sender, int32_t type, const double *v, int n);

/* Waits up to TIMEOUT_S for DONE(USER) to be true, checking every millisecond. */
bool fake_wait(bool (*done)(void *user), void *user, double timeout_s);
void fake_sleep_ms(int ms);

#endif
