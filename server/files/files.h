/* files.h -- instrument files in: bytes of an AFM, profilometer or interferometer file out as a
 * height map with its grid, physical size, units and what the file says about itself (issue 28).
 *
 * One module, one file per format behind this small interface. A reader never reads outside
 * [buf, buf + len): every access goes through the bounded readers of bytes.h. Heights come out
 * in metres, sizes in metres; a point the file marks as missing (NaN, a mask, a "no data"
 * value) comes out as NaN and is counted in map->missing. Knows nothing of HTTP or JSON; the
 * request layer (server/api) and the CLI use it.
 *
 *   ljgap__files_read(buf, len, format, channel, &map, &err)
 *       format: NULL or "" to recognise the format from its magic bytes and structure, else a
 *       format's name (ljgap__files_formats) to force it; channel: NULL or "" for the default
 *       (the height channel), else a channel's index ("0", "1", ...) or title.
 *       Returns 0, or LJGAP_FILES_UNKNOWN (no reader recognises the bytes, or an unknown
 *       format name: 415), LJGAP_FILES_BAD (a reader recognised the format but the file is
 *       truncated, corrupt or inconsistent: 422 bad-file; err says the format and the byte
 *       offset or the member), LJGAP_FILES_CHANNEL (no such channel: 422 at the channel),
 *       LJGAP_FILES_NOMEM, LJGAP_FILES_TOOBIG (the map would exceed LJGAP_FILES_MAX_POINTS).
 *   ljgap__files_map_free(&map) releases it (also after a failure: always safe).
 */
#ifndef LJGAP_FILES_H
#define LJGAP_FILES_H

#include <stddef.h>

#define LJGAP_FILES_UNKNOWN 1
#define LJGAP_FILES_BAD 2
#define LJGAP_FILES_CHANNEL 3
#define LJGAP_FILES_NOMEM 4
#define LJGAP_FILES_TOOBIG 5

#define LJGAP_FILES_MAX_POINTS (4096u * 4096u) /* 16 M points (128 MiB of doubles) */
#define LJGAP_FILES_MAX_CHANNELS 32
#define LJGAP_FILES_TEXT 128 /* the size of the text fields below */

typedef struct {
    size_t nx, ny;       /* points along x (a row) and rows (along y); ny = 1: a profile */
    double *z;           /* nx * ny heights in metres, row j at z[j * nx], NaN where missing */
    double size_x;       /* the physical size along x and y in metres: nx * dx and ny * dy */
    double size_y;       /*   (0 when the file does not state it: the query must give dx) */
    size_t missing;      /* points marked missing (NaN in z) */
    int periodic;        /* 1 when the file says the map is periodic, else 0 */
    double tip_radius;   /* the probe's tip radius in metres where stored, else 0 */
    const char *format;  /* the reader's name, e.g. "nanoscope" (static storage) */
    char channel[LJGAP_FILES_TEXT];    /* the title of the channel read */
    int channel_index;                 /* its index in channels[] */
    char channels[LJGAP_FILES_MAX_CHANNELS][LJGAP_FILES_TEXT]; /* every channel's title */
    int n_channels;
    char z_unit[32];                   /* the height unit the file states ("nm", "m", "V"...) */
    char instrument[LJGAP_FILES_TEXT]; /* instrument name/model where stored, else "" */
    char acquired[40];                 /* date of the scan, ISO 8601 where stored, else "" */
} ljgap__files_map;

typedef struct {
    char msg[256];      /* what is wrong, for the problem's detail */
    const char *format; /* the format it was read as (NULL when unknown) */
    long offset;        /* the byte offset of the fault, -1 when not applicable */
    char member[64];    /* the member of a container (X3P's zip) or "" */
} ljgap__files_err;

/* One format: its name, its extensions (for docs and messages only: recognition is by
 * content), whether bytes look like it (a cheap check of magic bytes and structure), and its
 * reader (channel already defaulted: NULL means the height channel). */
typedef struct {
    const char *name;       /* "nanoscope", "x3p", "sur", "gwy", "gsf", "netcdf", "metropro",
                             * "ibw", "park-tiff", "plu", "xyz" */
    const char *extensions; /* ".spm .000 .di" */
    const char *media_type; /* the format's own media type where one exists, else NULL */
    int (*probe)(const unsigned char *buf, size_t len);
    int (*read)(const unsigned char *buf, size_t len, const char *channel, ljgap__files_map *map,
                ljgap__files_err *err);
} ljgap__files_format;

int ljgap__files_read(const unsigned char *buf, size_t len, const char *format,
                     const char *channel, ljgap__files_map *map, ljgap__files_err *err);
void ljgap__files_map_free(ljgap__files_map *map);

/* The formats read, in recognition order, NULL-terminated. */
const ljgap__files_format *const *ljgap__files_formats(void);

/* The readers (one file each, server/files/FORMAT.c). */
extern const ljgap__files_format ljgap__files_nanoscope, ljgap__files_x3p, ljgap__files_sur,
    ljgap__files_gwy, ljgap__files_gsf, ljgap__files_netcdf, ljgap__files_metropro, ljgap__files_ibw,
    ljgap__files_park_tiff, ljgap__files_plu, ljgap__files_xyz;

/* ---- beside the readers: for the request layer, the CLI and the tests ---- */
/* The format of that name (case-insensitive), or NULL. */
const ljgap__files_format *ljgap__files_find(const char *name);
/* The format whose probe recognises buf (the registry's order), or NULL. */
const ljgap__files_format *ljgap__files_detect(const unsigned char *buf, size_t len);
/* "name (extensions), ..." of every format read, into out (for 415 details and --help). */
void ljgap__files_names(char *out, size_t size);
/* The channel a request names among map->channels: NULL or "" the height channel (the first
 * title starting with Height, else Topography, else ZSensor, else one naming a height such as
 * "Z sensor" or "Surface"; else channel 0), digits an index, else a title (exactly, then
 * ignoring case). Its index, or -1 with err->msg listing the channels (then the reader answers
 * LJGAP_FILES_CHANNEL). Readers call it once their titles are in map->channels. */
int ljgap__files_channel_pick(const ljgap__files_map *map, const char *channel,
                             ljgap__files_err *err);
/* Counts the NaN of map->z into map->missing (and returns it). */
size_t ljgap__files_count_missing(ljgap__files_map *map);
/* The largest rectangle of complete (non-NaN) points: its first column x0, first row y0,
 * width w and height h (all 0 when every point is missing); -1 when out of memory. */
int ljgap__files_largest_rect(const ljgap__files_map *map, size_t *x0, size_t *y0, size_t *w,
                             size_t *h);

/* The factor from a length unit ("m", "mm", "um", "µm" in UTF-8 or Latin-1, "~m", "micron",
 * "nm", "pm", "A", "Å", "km", "cm", "metre"...; surrounding blanks ignored) to metres, 0 when
 * unit is not a length. */
double ljgap__files_unit_scale(const char *unit);

#endif
