/*
 * session/player: time playback.  The cursor (playback_*: pure logic) and the player over the
 * time series cache (player_*): the scene's time steps made as extinction volumes with the
 * look (species, tints, transfer function) on the series' background thread.  No GL.
 */
#ifndef ANVIL_SESSION_PLAYER_H
#define ANVIL_SESSION_PLAYER_H

#include <stdbool.h>
#include <stdint.h>

#include "config/config.h"
#include "data/volume.h"
#include "data/wrf.h"
#include "optics/transfer.h"
#include "session/stats.h"

/* ---- playback: the time cursor (pure logic, no I/O) ----------------------------------- */

struct playback {
    int step, count;
    bool playing, loop;
    double speed;   /* steps per second */
    double acc;     /* fraction of a step accumulated */
    unsigned stalls; /* frames that wanted the next step before it was loaded */
};

void playback_init(struct playback *pb, int count, int step, double speed, bool loop);
/* Advances by DT seconds.  The cursor moves to the next step only once READY says it is loaded
 * (it waits there, counting stalls, rather than skip or block); at the end it stops (pausing)
 * unless LOOP.  Returns true when the step changed. */
bool playback_tick(struct playback *pb, double dt, bool (*ready)(void *user, int step),
                       void *user);

/* ---- the player: the time series cache over the scene's data --------------------------- */

/* How the volume is made from mass ratios, and the colour-mapped layers shown with it
 * (changed by the menu).  The menu's transfer editor edits layer 0. */
struct look {
    struct species_select select;
    struct species_tint tint;
    int layer_count; /* 0 .. TRANSFER_LAYER_MAX */
    struct transfer_layer layers[TRANSFER_LAYER_MAX];
    int slice_count; /* 0 .. TRANSFER_SLICE_MAX */
    struct transfer_slice slices[TRANSFER_SLICE_MAX];
    int edited; /* the layer the transfer editor edits, whose field its histogram counts */
};

/* The function the transfer editor shows: the edited layer's, or the default function of
 * QVAPOR without layers. */
void look_edited_transfer(const struct look *look, struct transfer_function *out);

/* The layer the transfer editor edits: EDITED where it names one of the layers, else 0. */
int look_edited_layer(const struct look *look);

void look_from_config(const struct config *cfg, struct look *look);

struct player;

struct player_desc {
    int prefetch;       /* -1: none; 0: default */
    double memory_mb;   /* 0: data.cache_memory */
    double delay_ms;    /* test hook: a slow reader */
    bool still;         /* nothing will play: no time series cache, no background thread */
    bool no_first;      /* do not make the first step (player_take_first) */
    bool histogram;     /* each step carries the histogram of the look's transfer field (for
                           the menu's transfer editor); without it that field (QVAPOR, say) is
                           read only while the transfer function shows it */
};

/* Opens the scene's time steps (the data files once), makes the step data.step on the
 * calling thread (player_take_first) and, unless D->still, starts the time series cache behind
 * it (data.cache_memory, data.prefetch, playback.loop).  What the loader needs is copied out of
 * CFG here: CFG may go afterwards.  NULL (logged) on failure.  No GL. */
struct player *player_create(const struct config *cfg, const struct player_desc *d);
void player_destroy(struct player *p);

/* Moves the first step's volume into OUT (the caller finishes it, or hands it back with
 * player_keep_first); false once it is taken. */
bool player_take_first(struct player *p, struct ext_volume *out);
/* Takes back the first step's volume (*VOL, as player_take_first gave it, zeroed here) once
 * the caller is done with it: the time series cache keeps it as that step's, so that the step
 * is not read again (series_adopt); without a series, or after a new look, it is freed. */
void player_keep_first(struct player *p, struct ext_volume *vol);
/* The WRF metadata of a WRF scene (terrain, lat/lon), or NULL.  Immutable; valid until
 * player_destroy; safe to read while the series' thread loads. */
const struct wrf_meta *player_wrf_meta(struct player *p);
/* STEP's WRF metadata (wrf_step_meta: a moving domain's own 2-D fields), or NULL as
 * player_wrf_meta; whether the domain moves in *MOVES. */
const struct wrf_meta *player_wrf_step_meta(struct player *p, int step, bool *moves);

int player_step_count(const struct player *p);
/* "2005-08-28_06:00:00" or "" (static per player, valid until destroy). */
const char *player_step_date(struct player *p, int step);
bool player_ready(struct player *p, int step);
/* Starts loading STEP in the background without showing it (series_want); no-op without a
 * series. */
void player_want(struct player *p, int step);
/* Whether the look can change the volume (storm and WRF/Isabel data: yes; test scenes and
 * extinction files: no). */
bool player_has_fields(const struct player *p);
/* Species the data holds. */
void player_species_present(const struct player *p, bool present[SPECIES_COUNT]);

/* Changes the look: cached steps are dropped and made again in the background. */
void player_set_look(struct player *p, const struct look *look);

/* The volume to show for WANT when it differs from what was last returned (a new step or a
 * new look) and is loaded; NULL otherwise (nothing new, or not loaded yet: never blocks).
 * *SHOWN receives the step on screen.  The pointer is valid until the next call. */
const struct ext_volume *player_poll(struct player *p, int want, int *shown);
/* As player_poll but waits for the load (the end of a scripted run). */
const struct ext_volume *player_wait(struct player *p, int want, int *shown);
/* Whether the step on screen is WANT with the current look. */
bool player_settled(const struct player *p, int want);
/* effects.temporal: the next volume, tracked apart from the one shown.  As player_poll
 * (or with WAIT as player_wait) for step WANT (-1: none wanted); *HELD is the step the
 * caller's next volume holds, -1 none. */
const struct ext_volume *player_poll_next(struct player *p, int want, bool wait,
                                              int *held);
/* Staged playback: the next volume (player_poll_next) becomes the one shown, as player_poll
 * would make it but without a second copy: returns its volume (valid as player_poll's), or
 * NULL when no next volume with the current look is held (nothing changes). */
const struct ext_volume *player_promote_next(struct player *p);
/* The step of the next volume held with the current look, or -1. */
int player_next_step(const struct player *p);
/* The identity (lightmaps_step_id) of the volume shown, or with NEXT of the next volume (0
 * when it is none, or made with an older look). */
uint64_t player_step_id(const struct player *p, bool next);

void player_stats(struct player *p, struct session_stats *st);

#endif
