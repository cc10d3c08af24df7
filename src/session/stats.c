/* --stats FILE.json: what a run did. */
#include "session/stats.h"

#include <stdio.h>
#include <stdlib.h>

#include "common/log.h"

void session_stats_add_view(struct session_stats *st)
{
    st->views++;
}

void session_stats_add_build(struct session_stats *st)
{
    st->light_builds++;
}

/* The first GPU_TIMINGS_KEPT times of T; null where one has not arrived. */
static void write_list(FILE *f, const struct gpu_timings *t)
{
    unsigned n = t->count < GPU_TIMINGS_KEPT ? t->count : GPU_TIMINGS_KEPT;
    fputc('[', f);
    for (unsigned i = 0; i < n; i++) {
        fputs(i ? ", " : "", f);
        if (t->known[i])
            fprintf(f, "%.4f", t->ms[i]);
        else
            fputs("null", f);
    }
    fputc(']', f);
}

/* TEXT as a JSON string (control characters left out). */
const char *session_piece_kind_name(enum session_piece_kind kind)
{
    static const char *const names[SESSION_PIECE_KINDS] = {"the stage's start", "the copy",
                                                           "the upload",        "the staged cells",
                                                           "the pair's cells",  "the light build"};
    return kind >= 0 && kind < SESSION_PIECE_KINDS ? names[kind] : "?";
}

static void write_string(FILE *f, const char *text)
{
    fputc('"', f);
    for (const char *p = text ? text : ""; *p; p++) {
        if (*p == '"' || *p == '\\')
            fputc('\\', f);
        if ((unsigned char)*p >= 0x20)
            fputc(*p, f);
    }
    fputc('"', f);
}

bool session_stats_json(const struct session_stats *st, int rank, const char *walls,
                        char **text, size_t *len)
{
    *text = NULL;
    *len = 0;
    FILE *f = open_memstream(text, len);
    if (!f) {
        log_error("--stats: out of memory");
        return false;
    }
    fprintf(f, "{\n  \"command\": ");
    write_string(f, st->command);
    if (rank >= 0) {
        fprintf(f, ",\n  \"rank\": %d,\n  \"walls\": ", rank);
        write_string(f, walls);
        fprintf(f, ",\n  \"sync_ms\": %.3f,\n  \"first_sync_ms\": %.3f", st->sync_ms,
                st->first_sync_ms);
    }
    fprintf(f, ",\n  \"device\": ");
    write_string(f, st->device);
    fprintf(f, ",\n  \"stopped_by\": ");
    if (st->stopped_by)
        write_string(f, st->stopped_by);
    else
        fputs("null", f);
    fprintf(f, ",\n  \"views\": %u,\n  \"light_map_builds\": %u,\n", st->views,
            st->light_builds);
    fprintf(f, "  \"view_ms\": ");
    write_list(f, &st->view_times);
    fprintf(f, ",\n  \"build_ms\": ");
    write_list(f, &st->build_times);
    fprintf(f, ",\n  \"light_map_bytes_dense\": %.0f,\n", st->light_bytes_dense);
    fprintf(f, "  \"light_map_bytes_compressed\": %.0f,\n", st->light_bytes_compressed);
    fprintf(f, "  \"gpu_bytes\": %zu,\n  \"nonfinite_pixels\": %zu,\n", st->gpu_bytes,
            st->nonfinite_pixels);
    fprintf(f, "  \"frames\": %u,\n  \"time_step\": %d,\n", st->frames, st->time_step);
    fprintf(f, "  \"cache_hits\": %u,\n  \"cache_misses\": %u,\n", st->cache_hits,
            st->cache_misses);
    fprintf(f, "  \"cache_loads\": %u,\n  \"cache_steps\": %d,\n", st->cache_loads,
            st->cache_steps);
    fprintf(f, "  \"frames_waited\": %u,\n  \"frames_stale\": %u,\n", st->frames_waited,
            st->frames_stale);
    fprintf(f, "  \"frames_held\": %u,\n", st->frames_held);
    fprintf(f, "  \"volume_uploads\": %u,\n  \"load_ms\": %.3f,\n  \"convert_ms\": %.3f,\n",
            st->volume_uploads, st->load_ms, st->convert_ms);
    fprintf(f, "  \"wait_ms\": %.3f,\n  \"upload_ms_total\": %.3f,\n", st->wait_ms,
            st->upload_ms_total);
    fprintf(f, "  \"volume_swaps\": %u,\n  \"prepare_ms\": %.3f,\n", st->volume_swaps,
            st->prepare_ms);
    fprintf(f, "  \"prepare_piece_max\": ");
    write_string(f, st->prepare_piece_max ? st->prepare_piece_max : "");
    fprintf(f, ",\n  \"prepare_piece_max_ms\": %.3f,\n", st->prepare_piece_max_ms);
    fprintf(f, "  \"prepare_kind_ms\": {");
    for (int k = 0; k < SESSION_PIECE_KINDS; k++) {
        fprintf(f, "%s", k ? ", " : "");
        write_string(f, session_piece_kind_name((enum session_piece_kind)k));
        fprintf(f, ": %.3f", st->prepare_kind_ms[k]);
    }
    fprintf(f, "},\n");
    fprintf(f, "  \"frame_ms_max\": %.3f,\n  \"loop_ms\": %.3f,\n  \"first_frame_ms\": %.3f,\n",
            st->frame_ms_max, st->loop_ms, st->first_frame_ms);
    fprintf(f, "  \"upload_bytes\": %.0f,\n", st->upload_bytes);
    if (st->counted) {
        /* Device-independent work of the views: per pixel drawn, and in all. */
        const struct render_counts *c = &st->counts;
        double rays = c->rays ? (double)c->rays : 1.0;
        fprintf(f, "  \"rays\": %llu,\n  \"rays_marched\": %llu,\n",
                (unsigned long long)c->rays, (unsigned long long)c->rays_marched);
        fprintf(f, "  \"beta_samples\": %llu,\n  \"light_reads\": %llu,\n",
                (unsigned long long)c->beta_samples, (unsigned long long)c->light_reads);
        fprintf(f, "  \"cells_read\": %llu,\n  \"steps_leapt\": %llu,\n",
                (unsigned long long)c->cells_read, (unsigned long long)c->steps_leapt);
        fprintf(f, "  \"beta_samples_per_pixel\": %.3f,\n  \"light_reads_per_pixel\": %.3f,\n",
                (double)c->beta_samples / rays, (double)c->light_reads / rays);
        fprintf(f, "  \"steps_leapt_per_pixel\": %.3f,\n", (double)c->steps_leapt / rays);
    }
    fprintf(f, "  \"volume_ms\": %.3f,\n  \"upload_ms\": %.3f,\n  \"total_ms\": %.3f\n}\n",
            st->volume_ms, st->upload_ms, st->total_ms);
    if (fclose(f) != 0 || !*text) {
        free(*text);
        *text = NULL;
        log_error("--stats: out of memory");
        return false;
    }
    return true;
}

bool session_stats_write(const struct session_stats *st, const char *path)
{
    char *buf;
    size_t len;
    if (!session_stats_json(st, -1, NULL, &buf, &len))
        return false;
    bool ok = file_write_atomic(path, buf, len);
    free(buf);
    return ok;
}
