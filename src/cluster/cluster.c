/* The ranks of an mpirun job through MPI, or one rank without it. */
#include "cluster/cluster.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"

#ifdef ANVIL_HAVE_MPI
#include <mpi.h>
#endif

static int rank, size = 1, local_rank;
static bool started;

bool cluster_available(void)
{
#ifdef ANVIL_HAVE_MPI
    return true;
#else
    return false;
#endif
}

/* Whether a process manager started us as one of several ranks (Open MPI, MPICH, PMIx). */
static bool launched_by_mpirun(void)
{
    static const char *const vars[] = {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"};
    for (size_t i = 0; i < sizeof(vars) / sizeof(vars[0]); i++)
        if (getenv(vars[i]))
            return true;
    return false;
}

bool cluster_init(int *argc, char ***argv)
{
    if (!launched_by_mpirun())
        return true;
#ifdef ANVIL_HAVE_MPI
    if (MPI_Init(argc, argv) != MPI_SUCCESS) {
        log_error("MPI: could not start");
        return false;
    }
    started = true;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    MPI_Comm local;
    MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, rank, MPI_INFO_NULL, &local);
    MPI_Comm_rank(local, &local_rank);
    MPI_Comm_free(&local);
    /* A failed call ends the job rather than hang it. */
    MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_ARE_FATAL);
    char name[32];
    snprintf(name, sizeof(name), "anvil[%d]", rank);
    if (size > 1)
        log_set_name(name);
    if (rank != 0 && log_get_level() >= LOG_INFO)
        log_set_level(LOG_WARN); /* the other ranks say only what goes wrong */
    return true;
#else
    (void)argc;
    (void)argv;
    log_warn("started by mpirun, but this anvil was built without MPI: one process, every wall");
    return true;
#endif
}

void cluster_finish(void)
{
#ifdef ANVIL_HAVE_MPI
    if (started)
        MPI_Finalize();
#endif
    started = false;
}

int cluster_rank(void)
{
    return rank;
}

int cluster_size(void)
{
    return size;
}

int cluster_local_rank(void)
{
    return local_rank;
}

bool cluster_active(void)
{
    return size > 1;
}

void cluster_broadcast(void *buf, size_t len)
{
#ifdef ANVIL_HAVE_MPI
    if (started && size > 1)
        MPI_Bcast(buf, (int)len, MPI_BYTE, 0, MPI_COMM_WORLD);
#else
    (void)buf;
    (void)len;
#endif
}

uint32_t cluster_and(uint32_t mine)
{
#ifdef ANVIL_HAVE_MPI
    if (started && size > 1) {
        uint32_t all = 0;
        MPI_Allreduce(&mine, &all, 1, MPI_UINT32_T, MPI_BAND, MPI_COMM_WORLD);
        return all;
    }
#endif
    return mine;
}

bool cluster_all(bool mine)
{
    return cluster_and(mine ? 1u : 0u) != 0;
}

void cluster_barrier(void)
{
#ifdef ANVIL_HAVE_MPI
    if (started && size > 1)
        MPI_Barrier(MPI_COMM_WORLD);
#endif
}

char **cluster_gather_text(const char *text)
{
    if (size <= 1 || !started) {
        char **out = calloc(1, sizeof(char *));
        if (out)
            out[0] = strdup(text);
        return out;
    }
#ifdef ANVIL_HAVE_MPI
    int len = (int)strlen(text) + 1;
    int *lens = rank == 0 ? calloc((size_t)size, sizeof(int)) : NULL;
    if (rank == 0 && !lens) {
        log_error("out of memory");
        cluster_abort(4);
    }
    MPI_Gather(&len, 1, MPI_INT, lens, 1, MPI_INT, 0, MPI_COMM_WORLD);
    int *offsets = NULL;
    char *all = NULL;
    int total = 0;
    if (rank == 0) {
        offsets = calloc((size_t)size, sizeof(int));
        for (int i = 0; i < size; i++) {
            offsets[i] = total;
            total += lens[i];
        }
        all = malloc((size_t)total);
        if (!offsets || !all) {
            log_error("out of memory");
            cluster_abort(4);
        }
    }
    MPI_Gatherv(text, len, MPI_CHAR, all, lens, offsets, MPI_CHAR, 0, MPI_COMM_WORLD);
    char **out = NULL;
    if (rank == 0) {
        out = calloc((size_t)size, sizeof(char *));
        for (int i = 0; out && i < size; i++)
            out[i] = strdup(all + offsets[i]);
    }
    free(lens);
    free(offsets);
    free(all);
    return out;
#else
    return NULL;
#endif
}

void cluster_free_texts(char **texts)
{
    if (!texts)
        return;
    for (int i = 0; i < size; i++)
        free(texts[i]);
    free(texts);
}

void cluster_gather_u64(uint64_t value, uint64_t *out)
{
#ifdef ANVIL_HAVE_MPI
    if (started && size > 1) {
        MPI_Gather(&value, 1, MPI_UINT64_T, out, 1, MPI_UINT64_T, 0, MPI_COMM_WORLD);
        return;
    }
#endif
    out[0] = value;
}

_Noreturn void cluster_abort(int code)
{
#ifdef ANVIL_HAVE_MPI
    if (started && size > 1)
        MPI_Abort(MPI_COMM_WORLD, code);
#endif
    exit(code);
}

uint64_t cluster_hash(uint64_t hash, const void *data, size_t len)
{
    const unsigned char *p = data;
    for (size_t i = 0; i < len; i++) {
        hash ^= p[i];
        hash *= 1099511628211ull;
    }
    return hash;
}
