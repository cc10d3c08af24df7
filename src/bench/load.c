#include "bench/load.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "common/log.h"
#include "data/source.h"
#include "data/synth.h"
#include "data/wrf_write.h"
#include "optics/transfer.h"

/* Resident memory now and at its peak since the last reset, MiB (Linux: /proc/self/status;
 * NAN elsewhere). */
static void memory_mb(double *rss, double *hwm)
{
    *rss = *hwm = NAN;
    FILE *f = fopen("/proc/self/status", "r");
    if (!f)
        return;
    char line[256];
    while (fgets(line, sizeof(line), f)) {
        long kb;
        if (sscanf(line, "VmRSS: %ld kB", &kb) == 1)
            *rss = kb / 1024.0;
        else if (sscanf(line, "VmHWM: %ld kB", &kb) == 1)
            *hwm = kb / 1024.0;
    }
    fclose(f);
}

/* Starts a peak measurement: the peak is reset to what is resident now (Linux's clear_refs
 * "5"); returns the resident MiB. */
static double peak_start(void)
{
    FILE *f = fopen("/proc/self/clear_refs", "w");
    if (f) {
        fputs("5", f);
        fclose(f);
    }
    double rss, hwm;
    memory_mb(&rss, &hwm);
    return rss;
}

static double peak_since(double start)
{
    double rss, hwm;
    memory_mb(&rss, &hwm);
    return hwm - start;
}

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof(*v), compare_doubles);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

bool bench_write_storm_series(const char *path, const int n[3], int steps)
{
    struct wrf_writer *w = NULL;
    for (int s = 0; s < steps; s++) {
        struct synth_desc sd;
        synth_desc_defaults(&sd);
        sd.kind = SYNTH_STORM;
        memcpy(sd.n, n, sizeof(sd.n));
        sd.extent_m[0] = sd.extent_m[1] = 200000.0;
        sd.extent_m[2] = 16000.0;
        sd.time = steps > 1 ? 0.3 + 0.4 * s / (steps - 1) : 0.5;
        struct field_volume fv;
        if (!synth_storm_fields(&sd, &fv)) {
            wrf_writer_destroy(w);
            return false;
        }
        if (!w)
            w = wrf_writer_create(path, &fv.grid, &(struct wrf_write_desc){.cen_lat = 25.0,
                                                                            .cen_lon = -80.0});
        char date[32];
        snprintf(date, sizeof(date), "2000-01-01_00:%02d:00", 10 * s);
        bool ok = w && wrf_writer_add(w, &fv, date);
        field_volume_finish(&fv);
        if (!ok) {
            wrf_writer_destroy(w);
            return false;
        }
        log_info("bench: step %d of %d written", s + 1, steps);
    }
    return wrf_writer_finish(w);
}

#define MAX_PAIRS 64

bool bench_load(const struct bench_load_desc *d, struct bench_load_result *out)
{
    memset(out, 0, sizeof(*out));
    const int big[3] = {500, 500, 100}, small[3] = {64, 64, 20};
    memcpy(out->n, d->quick ? small : big, sizeof(out->n));
    out->steps = 2;
    out->rounds = d->rounds > 0 ? d->rounds : d->quick ? 1 : 3;
    if (out->steps * out->rounds > MAX_PAIRS)
        out->rounds = MAX_PAIRS / out->steps;
    char path[4096];
    const char *dir = d->dir ? d->dir : getenv("TMPDIR");
    snprintf(path, sizeof(path), "%s/anvil-bench-load-%ld.nc", dir && dir[0] ? dir : "/tmp",
             (long)getpid());
    log_info("bench: load: writing a %d x %d x %d series of %d steps to %s", out->n[0],
             out->n[1], out->n[2], out->steps, path);
    if (!bench_write_storm_series(path, out->n, out->steps)) {
        remove(path);
        return false;
    }
    /* The load as a data scene makes it: the defaults (no QVAPOR, no temperature or wind). */
    const char *files[] = {path};
    struct data_source_desc sd = {.format = DATA_SOURCE_WRF, .files = files, .file_count = 1};
    wrf_desc_defaults(&sd.wrf);
    optics_params_defaults(&sd.optics);
    species_select_defaults(&sd.select);
    struct data_source *src = data_source_open(&sd);
    bool ok = src != NULL;
    double plain[MAX_PAIRS], load[MAX_PAIRS], rd[MAX_PAIRS], cv[MAX_PAIRS], ratio[MAX_PAIRS];
    double vapour[MAX_PAIRS], vapour_ratio[MAX_PAIRS];
    int pairs = 0;
    for (int r = 0; r < out->rounds && ok; r++) {
        for (int s = 0; s < out->steps && ok; s++) {
            double tp = 0.0, tl = 0.0, lr = 0.0, lc = 0.0, tv = 0.0;
            for (int which = 0; which < 3 && ok; which++) {
                int way = (which + r + s) % 3; /* the order turns from pair to pair */
                bool do_plain = way == 0;
                double base = peak_start();
                double t0 = time_now_ms();
                if (way == 2) {
                    /* As anvil run's player loads it: the menu's transfer editor counts the
                     * water vapour on the way. */
                    struct transfer_function tf;
                    transfer_defaults(&tf, TRANSFER_FIELD_QVAPOR);
                    struct transfer_histogram h;
                    transfer_histogram_init(&h, tf.field, tf.lo, tf.hi);
                    struct ext_volume v;
                    ok = data_source_load_ext(src, s, &sd.optics, &sd.select, &h, &v);
                    tv = time_now_ms() - t0;
                    ext_volume_finish(&v);
                } else if (do_plain) {
                    double bytes = 0.0;
                    ok = wrf_read_plain(data_source_wrf(src), s, &sd.wrf, &bytes);
                    tp = time_now_ms() - t0;
                    out->step_mb = bytes / 1048576.0;
                    double pk = peak_since(base);
                    out->plain_peak_mb = pk > out->plain_peak_mb ? pk : out->plain_peak_mb;
                } else {
                    struct ext_volume v;
                    ok = data_source_load(src, s, &v, &lr, &lc);
                    tl = time_now_ms() - t0;
                    double pk = peak_since(base);
                    out->load_peak_mb = pk > out->load_peak_mb ? pk : out->load_peak_mb;
                    out->volume_mb = (double)grid3_count(&v.grid) * 2 * sizeof(float) /
                                     1048576.0;
                    ext_volume_finish(&v);
                }
            }
            if (!ok)
                break;
            plain[pairs] = tp;
            load[pairs] = tl;
            rd[pairs] = lr;
            cv[pairs] = lc;
            ratio[pairs] = tl / tp;
            vapour[pairs] = tv;
            vapour_ratio[pairs] = tv / tp;
            pairs++;
            log_info("bench: load: round %d step %d: plain read %.0f ms, load %.0f ms (%.2f x), "
                     "with the vapour's histogram %.0f ms (%.2f x)",
                     r + 1, s, tp, tl, tl / tp, tv, tv / tp);
        }
    }
    data_source_close(src);
    remove(path);
    if (!ok || pairs == 0)
        return false;
    out->plain_ms = median(plain, pairs);
    out->load_ms = median(load, pairs);
    out->read_ms = median(rd, pairs);
    out->convert_ms = median(cv, pairs);
    out->ratio = median(ratio, pairs);
    out->vapour_ms = median(vapour, pairs);
    out->vapour_ratio = median(vapour_ratio, pairs);
    return true;
}

void bench_write_load_table(FILE *f, const struct bench_load_desc *d,
                            const struct bench_load_result *r)
{
    fprintf(f, "| measure | plain NetCDF read | anvil's load | load ÷ plain |\n");
    fprintf(f, "| --- | ---: | ---: | ---: |\n");
    fprintf(f, "| a step, ms (median) | %.0f | %.0f | **%.2f** |\n", r->plain_ms, r->load_ms,
            r->ratio);
    fprintf(f, "| ... of which reading, checks, resampling and extinction (slab by slab), ms | | "
               "%.0f | |\n",
            r->read_ms);
    fprintf(f, "| ... of which after the read (the height scale), ms | | %.0f | |\n",
            r->convert_ms);
    fprintf(f,
            "| a step with the menu's histogram of the water vapour (QVAPOR read too, as "
            "`anvil run` loads it), ms | | %.0f | **%.2f** |\n",
            r->vapour_ms, r->vapour_ratio);
    fprintf(f, "| peak memory above the process's, MiB | %.0f | %.0f | %.2f |\n",
            r->plain_peak_mb, r->load_peak_mb,
            r->plain_peak_mb > 0.0 ? r->load_peak_mb / r->plain_peak_mb : 0.0);
    fprintf(f,
            "\nA %d × %d × %d WRF series of the procedural storm (%d steps, %.0f MiB read a "
            "step; the extinction volume a load returns is %.0f MiB), %d round%s, every step "
            "all three ways each round, the order turning from step to step; a ratio is the median "
            "of the "
            "side-by-side pairs.  The plain read is one `nc_get_vara` per variable (the "
            "species, PH, PHB, P, PB, T) into memory; the load reads the same variables a "
            "slab of rows at a time (`wrf_read_step_ext`), and with the menu (`anvil run`) "
            "QVAPOR too, for the transfer editor's histogram.  Goal: load ÷ plain ≤ 1.5: "
            "%s.\n",
            r->n[0], r->n[1], r->n[2], r->steps, r->step_mb, r->volume_mb, r->rounds,
            r->rounds == 1 ? "" : "s", r->ratio <= 1.5 ? "met" : "not met");
    (void)d;
}
