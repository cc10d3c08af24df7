#include "data/nclock.h"

#include <pthread.h>

static pthread_once_t once = PTHREAD_ONCE_INIT;
static pthread_mutex_t lock;

static void init_lock(void)
{
    pthread_mutexattr_t attr;
    pthread_mutexattr_init(&attr);
    pthread_mutexattr_settype(&attr, PTHREAD_MUTEX_RECURSIVE);
    pthread_mutex_init(&lock, &attr);
    pthread_mutexattr_destroy(&attr);
}

void data_nc_lock(void)
{
    pthread_once(&once, init_lock);
    pthread_mutex_lock(&lock);
}

void data_nc_unlock(void)
{
    pthread_mutex_unlock(&lock);
}
