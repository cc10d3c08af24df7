/*
 * bench/paraview: the ParaView side of the views benchmark.  The storm's volume goes to an
 * extinction file, and a ParaView script (src/bench/paraview_views.py, run by pvbatch, under
 * xvfb-run when there is no display) renders the same views of it with VTK's volumetric
 * shadows and writes views-paraview.md beside anvil's numbers.  The only code in the program
 * that starts another program.  No GL; where the script lies is the caller's to say.
 */
#ifndef ANVIL_BENCH_PARAVIEW_H
#define ANVIL_BENCH_PARAVIEW_H

#include <stdbool.h>
#include <stdio.h>

#include "bench/bench.h"
#include "data/volume.h"

struct bench_paraview_desc {
    const char *script;    /* paraview_views.py */
    const char *cache_dir; /* where the volume's extinction file goes (created) */
    const char *out_dir;   /* where the script writes views-paraview.md */
    double sun_azimuth_deg, sun_elevation_deg;
    int width, height, repeats; /* as anvil's views were measured */
    FILE *report;          /* progress lines ("running pvbatch", "not available"); may be NULL */
};

/* Times ParaView on VOL's views, given anvil's N rows ROWS for its table.  ParaView missing
 * (no pvbatch on PATH) is not an error: it is reported and true returned.  False (logged) when
 * the volume cannot be written or the script fails. */
bool bench_paraview_views(const struct bench_paraview_desc *d, const struct ext_volume *vol,
                          const struct bench_views_row *rows, int n);

#endif
