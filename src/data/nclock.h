/*
 * data/nclock: NetCDF-C is not thread safe, so every part of data/ that calls nc_* holds this
 * one process-wide lock for the whole of an operation (open, read a step, write a step).  The
 * lock is recursive: an operation may call another.
 */
#ifndef ANVIL_DATA_NCLOCK_H
#define ANVIL_DATA_NCLOCK_H

void data_nc_lock(void);
void data_nc_unlock(void);

#endif
