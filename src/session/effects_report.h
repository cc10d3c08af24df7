/*
 * session/effects_report: what anvil effects says about a config: every effect's decision
 * with its reason, made from the facts a session would measure (the first time step's volume
 * under the first sun, the time steps, the views of the config's camera or of a display with
 * a fixed head, the HMD) and how the light map's nodes will lie.  Plain CPU work: no GL, no
 * windows; the files read are the config's data.  Printing is the caller's.  The facts are
 * gathered as a session gathers them (effects_gather), the views laid out without a device:
 * an HMD's come from its device, so for an HMD they count as unknown.
 */
#ifndef ANVIL_SESSION_EFFECTS_REPORT_H
#define ANVIL_SESSION_EFFECTS_REPORT_H

#include <stdbool.h>

#include "config/config.h"
#include "config/display_config.h"
#include "light/light.h"
#include "session/effects.h"

struct effects_report_desc {
    const struct display_config *display; /* decide for its views; NULL: the config's camera */
    bool run;            /* decide for anvil run: the sun can move, the views change */
    bool scripted;       /* a scripted render (--input): time may play */
};

struct effects_report {
    struct effects effects;
    struct light_settings light; /* the light map the decisions ask for */
    bool grid_ok;                /* the light grid below could be laid out (else logged) */
    struct light_grid grid;      /* its nodes for the first sun (docs/lightmap.md, "Sheared
                                    grid") */
    double plane_m;              /* distance between the grid's node planes along w, metres */
};

/* Decides CFG's effects for D into OUT.  False (logged) when the volume cannot be built or
 * measured or the display config cannot be read; a light grid that cannot be laid out is
 * reported by OUT->grid_ok, after the decisions. */
bool effects_report_make(const struct config *cfg, const struct effects_report_desc *d,
                         struct effects_report *out);

#endif
