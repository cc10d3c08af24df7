/*
 * cluster: the processes of one anvil started by mpirun, one rank per render node (or GPU),
 * through MPI (Open MPI from Debian); the only code that includes mpi.h.  Rank 0 owns the input
 * and the clock; every frame it broadcasts the frame state and the other ranks draw their walls
 * from it.  Without MPI in the build, or when not started by mpirun, there is one rank and
 * every call here is a no-op (a broadcast leaves the bytes, a reduction returns its own value).
 *
 * Must not know: the session, displays, GL (the frame loop in app/ uses it).
 */
#ifndef ANVIL_CLUSTER_H
#define ANVIL_CLUSTER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* Starts MPI when this process is one rank of an mpirun job (its environment says so); else
 * one rank.  False (logged) when MPI was asked for and could not start. */
bool cluster_init(int *argc, char ***argv);
/* Ends MPI (all ranks must call it). */
void cluster_finish(void);

int cluster_rank(void);
int cluster_size(void);
/* The rank among those on the same host (for choosing its GPU). */
int cluster_local_rank(void);
/* Whether there is more than one rank. */
bool cluster_active(void);
/* Whether this build can run on a cluster at all. */
bool cluster_available(void);

/* LEN bytes of BUF from rank 0 to every rank. */
void cluster_broadcast(void *buf, size_t len);
/* Bitwise AND of MINE over the ranks, on every rank. */
uint32_t cluster_and(uint32_t mine);
/* Whether every rank said true. */
bool cluster_all(bool mine);
void cluster_barrier(void);
/* Every rank's TEXT, joined on rank 0 in rank order (the caller frees; NULL elsewhere). */
char **cluster_gather_text(const char *text);
void cluster_free_texts(char **texts);
/* Every rank's 64-bit VALUE on rank 0 into OUT (cluster_size entries; ignored elsewhere). */
void cluster_gather_u64(uint64_t value, uint64_t *out);
/* Ends the whole job from any rank with exit code CODE (after a message was logged). */
_Noreturn void cluster_abort(int code);

/* FNV-1a over LEN bytes, continuing from HASH (start with 1469598103934665603). */
uint64_t cluster_hash(uint64_t hash, const void *data, size_t len);

#endif
