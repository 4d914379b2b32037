/*
 * trajsurf - grid in, interpolating bicubic B-spline surface out.
 *
 *   trajsurf [-n N] [-o samples.csv] [-s picture.svg] [-x DX] [-y DY] [-z ZSCALE] grid.csv
 *
 * Input (one of, detected from the first line):
 *   a CSV with header "i,j,x,y,z": grid row i, column j and the point;
 *     every (i, j) of an M x N grid exactly once, in any order;
 *   a matrix of heights: one grid row per line, comma-separated numbers;
 *     x = column * DX, y = row * DY (defaults 1).
 * Output:
 *   samples CSV "u,v,x,y,z" on N steps per grid cell in each direction
 *     (u, v in grid units, so grid point (i, j) is the sample u = i, v = j,
 *     and the surface passes through it exactly), computed by forward
 *     differences (lib/spline/surf); "-" or no -o: stdout;
 *   picture (-s): an SVG wireframe in isometric projection, heights
 *     multiplied by ZSCALE, the grid points drawn as dots.
 * Exit status 0, 1 on bad input (message "file:line: what" on stderr), 2 on usage,
 * 3 when writing an output failed (as trajreplay).
 */
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "surf.h"
#include "stdfds.h"
#include "version.h"

#define DIM 3
#define GRID_MAX 4096   /* rows or columns */
#define SAMPLES_MAX 256 /* steps per cell */
#define SVG_W 900.0
#define SVG_H 700.0
#define SVG_MARGIN 30.0

typedef struct {
    size_t m, n;
    double *g; /* m*n*DIM */
} grid_t;

static void usage(FILE *f)
{
    fputs("usage: trajsurf [-n steps] [-o samples.csv] [-s picture.svg] "
          "[-x dx] [-y dy] [-z zscale] grid.csv\n",
          f);
}

static void help(void)
{
    usage(stdout);
    fputs("Fit an interpolating bicubic B-spline surface through a grid and sample it.\n"
          "\n"
          "  grid.csv             \"i,j,x,y,z\" rows (every cell of an M x N grid once),\n"
          "                       or a matrix of heights, one grid row per line\n"
          "  -n, --steps N        samples per grid cell in each direction (default 8,\n"
          "                       1 to 256)\n"
          "  -o, --output FILE    samples CSV \"u,v,x,y,z\" (default stdout; \"-\" = stdout)\n"
          "  -s, --svg FILE       isometric wireframe picture\n"
          "  -x, --dx DX          column spacing of a height matrix, > 0 (default 1)\n"
          "  -y, --dy DY          row spacing of a height matrix, > 0 (default 1)\n"
          "  -z, --zscale Z       height factor in the picture (default 1)\n"
          "  -h, --help           this text\n"
          "  -V, --version        version\n"
          "\n"
          "Exit status: 0 ok, 1 bad input (file:line: what, on stderr), 2 usage, 3 an\n"
          "output could not be written.\n",
          stdout);
}

static int parse_row(char *line, double *v, int max)
{
    int n = 0;
    char *p = line;

    while (*p) {
        char *end;
        double x;
        while (*p == ' ' || *p == '\t')
            p++;
        if (*p == '\0' || *p == '\n' || *p == '\r')
            break;
        if (n == max)
            return -1;
        errno = 0;
        x = strtod(p, &end);
        if (end == p || errno || !isfinite(x))
            return -1;
        v[n++] = x;
        p = end;
        while (*p == ' ' || *p == '\t')
            p++;
        if (*p == ',')
            p++;
        else if (*p && *p != '\n' && *p != '\r')
            return -1;
    }
    return n;
}

/* The rows of the open file f: *indexed = 1 for "i,j,x,y,z" rows (5 numbers
 * each), 0 for a matrix (*ncols numbers each), -1 if there was no row.
 * 0 or -1 with a message; *rows is the caller's to free either way. */
static int read_rows(FILE *f, const char *path, double **rows, size_t **lines, size_t *nrows,
                     size_t *ncols, int *indexed)
{
    char *line = NULL; /* whole lines of any length (a row of GRID_MAX numbers is long) */
    size_t linecap = 0;
    ssize_t len;
    double v[GRID_MAX];
    size_t cap = 0, lineno = 0;
    int rc = 0;

    while ((len = getline(&line, &linecap, f)) >= 0) {
        int n;
        lineno++;
        if (strlen(line) != (size_t)len) {
            fprintf(stderr, "%s:%zu: NUL byte in the line\n", path, lineno);
            rc = -1;
            break;
        }
        if (line[0] == '#' || line[strspn(line, " \t\r\n")] == '\0')
            continue;
        if (*indexed < 0) {
            *indexed = strncmp(line, "i,j,x,y,z", 9) == 0;
            if (*indexed)
                continue;
        }
        n = parse_row(line, v, *indexed ? 5 : GRID_MAX);
        if (n <= 0 || (*indexed && n != 5)) {
            fprintf(stderr, "%s:%zu: expected %s\n", path, lineno,
                    *indexed ? "i,j,x,y,z, five finite numbers"
                             : "finite numbers separated by commas");
            rc = -1;
            break;
        }
        if (!*indexed) {
            if (*ncols == 0)
                *ncols = (size_t)n;
            if ((size_t)n != *ncols) {
                fprintf(stderr, "%s:%zu: %d values, first row had %zu\n", path, lineno, n, *ncols);
                rc = -1;
                break;
            }
        }
        if (*nrows == cap) {
            size_t nc = cap ? 2 * cap : 64;
            double *r = realloc(*rows, nc * (*indexed ? 5 : *ncols) * sizeof *r);
            if (r)
                *rows = r;
            size_t *l = r ? realloc(*lines, nc * sizeof *l) : NULL;
            if (!l) {
                fprintf(stderr, "%s: out of memory\n", path);
                rc = -1;
                break;
            }
            *lines = l;
            cap = nc;
        }
        memcpy(*rows + *nrows * (*indexed ? 5 : *ncols), v, (size_t)n * sizeof *v);
        (*lines)[*nrows] = lineno;
        (*nrows)++;
    }
    free(line);
    return rc;
}

/* The grid from "i,j,x,y,z" rows: every (i, j) of an m x n grid exactly once. */
static int grid_from_indexed(const double *rows, const size_t *lines, size_t nrows,
                             const char *path, grid_t *gr)
{
    size_t m = 0, n = 0, i;
    unsigned char *seen = NULL;
    int rc = -1;
    for (i = 0; i < nrows; i++) {
        double a = rows[i * 5], b = rows[i * 5 + 1];
        if (a < 0 || b < 0 || fabs(a - floor(a)) > 0.0 || fabs(b - floor(b)) > 0.0 ||
            a >= GRID_MAX || b >= GRID_MAX) {
            fprintf(stderr,
                    "%s:%zu: bad grid index (%g, %g): i and j are whole numbers from 0, below "
                    "%d\n",
                    path, lines[i], a, b, GRID_MAX);
            return -1;
        }
        if ((size_t)a + 1 > m)
            m = (size_t)a + 1;
        if ((size_t)b + 1 > n)
            n = (size_t)b + 1;
    }
    if (m * n != nrows) {
        fprintf(stderr, "%s: %zu points do not fill a %zu x %zu grid\n", path, nrows, m, n);
        return -1;
    }
    gr->g = malloc(m * n * DIM * sizeof *gr->g);
    seen = calloc(m * n, 1);
    if (!gr->g || !seen)
        goto out;
    for (i = 0; i < nrows; i++) {
        size_t k = (size_t)rows[i * 5] * n + (size_t)rows[i * 5 + 1];
        if (seen[k]++) {
            fprintf(stderr, "%s:%zu: grid point (%g, %g) given twice\n", path, lines[i],
                    rows[i * 5], rows[i * 5 + 1]);
            goto out;
        }
        memcpy(gr->g + k * DIM, rows + i * 5 + 2, DIM * sizeof *gr->g);
    }
    gr->m = m;
    gr->n = n;
    rc = 0;
out:
    free(seen);
    return rc;
}

/* The grid from a matrix of heights: x = column * dx, y = row * dy. */
static int grid_from_matrix(const double *rows, size_t nrows, size_t ncols, double dx, double dy,
                            grid_t *gr)
{
    size_t r, c;
    gr->g = malloc(nrows * ncols * DIM * sizeof *gr->g);
    if (!gr->g)
        return -1;
    for (r = 0; r < nrows; r++)
        for (c = 0; c < ncols; c++) {
            double *p = gr->g + (r * ncols + c) * DIM;
            p[0] = (double)c * dx;
            p[1] = (double)r * dy;
            p[2] = rows[r * ncols + c];
        }
    gr->m = nrows;
    gr->n = ncols;
    return 0;
}

/* Read the grid; 0 or -1 with a message. */
static int read_grid(const char *path, double dx, double dy, grid_t *gr)
{
    FILE *f = strcmp(path, "-") ? fopen(path, "r") : stdin;
    double *rows = NULL;
    size_t *lines = NULL, nrows = 0, ncols = 0;
    int indexed = -1, rc = -1;

    if (!f) {
        fprintf(stderr, "%s: %s\n", path, strerror(errno));
        return -1;
    }
    if (read_rows(f, path, &rows, &lines, &nrows, &ncols, &indexed) < 0)
        goto out;
    if (indexed == 1 ? grid_from_indexed(rows, lines, nrows, path, gr) < 0
                     : grid_from_matrix(rows, nrows, ncols, dx, dy, gr) < 0)
        goto out;
    if (gr->m < 2 || gr->n < 2) {
        fprintf(stderr, "%s: need a grid of at least 2 x 2 points\n", path);
        goto out;
    }
    rc = 0;
out:
    if (f != stdin)
        fclose(f);
    free(rows);
    free(lines);
    return rc;
}

/* Isometric projection: screen x to the right, y down; depth grows away from the viewer. */
static void project(const double *p, double zscale, double *sx, double *sy)
{
    const double c30 = 0.8660254037844386, s30 = 0.5;
    *sx = (p[0] - p[1]) * c30;
    *sy = -((p[0] + p[1]) * s30 + p[2] * zscale);
}

typedef struct {
    double depth;
    size_t a, b; /* lower-left sample of the cell */
} cell_t;

static int far_first(const void *x, const void *y)
{
    double dx = ((const cell_t *)x)->depth, dy = ((const cell_t *)y)->depth;
    return dx < dy ? 1 : (dx > dy ? -1 : 0);
}

/*
 * Painter's algorithm: every sample cell is a filled quadrilateral, drawn
 * from the back (largest x + y) to the front, coloured by its mean height
 * (blue low, red high).  Good enough for height fields seen from above;
 * a surface folding over itself may show ordering errors (no z-buffer).
 */

/* Flush and close an output (stdout is flushed, not closed): 0, or -1 with
 * "name: error" on stderr if any write to it failed (a full disk, EIO).  The
 * caller sets errno = 0 before writing, so a failed write leaves its errno. */
static int close_output(FILE *f, const char *name)
{
    int err = ferror(f) ? (errno ? errno : EIO) : 0; /* a write failed: its errno */
    if (fflush(f) != 0 && !err)
        err = errno ? errno : EIO;
    if (f != stdout && fclose(f) != 0 && !err)
        err = errno ? errno : EIO;
    if (!err)
        return 0;
    fprintf(stderr, "%s: %s\n", name, strerror(err));
    return -1;
}
/* The (su - 1) x (sv - 1) cells of the sampled surface, farthest first
 * (painter's algorithm). */
static void sort_cells(cell_t *cells, const double *smp, size_t su, size_t sv)
{
    size_t a, b, k = 0;
    for (a = 0; a + 1 < su; a++)
        for (b = 0; b + 1 < sv; b++) {
            const double *p = smp + (a * sv + b) * DIM, *q = smp + ((a + 1) * sv + b + 1) * DIM;
            cells[k].depth = p[0] + p[1] + q[0] + q[1];
            cells[k].a = a;
            cells[k].b = b;
            k++;
        }
    qsort(cells, k, sizeof *cells, far_first);
}

static int write_svg(const char *path, const grid_t *gr, const double *smp, size_t su, size_t sv,
                     double zscale)
{
    errno = 0;
    FILE *f = fopen(path, "w");
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY, sc, ox, oy;
    double zlo = INFINITY, zhi = -INFINITY;
    size_t k, nc = (su - 1) * (sv - 1);
    cell_t *cells = malloc(nc * sizeof *cells);

    if (!f || !cells) {
        fprintf(stderr, "%s: %s\n", path, f ? "out of memory" : strerror(errno));
        if (f)
            fclose(f);
        free(cells);
        return -1;
    }
    for (k = 0; k < su * sv; k++) {
        double X, Y;
        project(smp + k * DIM, zscale, &X, &Y);
        x0 = fmin(x0, X);
        x1 = fmax(x1, X);
        y0 = fmin(y0, Y);
        y1 = fmax(y1, Y);
        zlo = fmin(zlo, smp[k * DIM + 2]);
        zhi = fmax(zhi, smp[k * DIM + 2]);
    }
    sc = fmin((SVG_W - 2 * SVG_MARGIN) / fmax(x1 - x0, 1e-12),
              (SVG_H - 2 * SVG_MARGIN - 20) / fmax(y1 - y0, 1e-12));
    ox = 0.5 * (SVG_W - (x1 - x0) * sc);
    oy = 20 + 0.5 * (SVG_H - 20 - (y1 - y0) * sc);
    fprintf(f,
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" "
            "viewBox=\"0 0 %.0f %.0f\">\n"
            "<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n"
            "<g stroke=\"#333\" stroke-width=\"0.3\">\n",
            SVG_W, SVG_H, SVG_W, SVG_H);
    sort_cells(cells, smp, su, sv);
    for (k = 0; k < nc; k++) {
        static const size_t da[4] = {0, 1, 1, 0}, db[4] = {0, 0, 1, 1};
        double zm = 0.0, q;
        int c;
        fprintf(f, "<polygon points=\"");
        for (c = 0; c < 4; c++) {
            const double *p = smp + ((cells[k].a + da[c]) * sv + cells[k].b + db[c]) * DIM;
            double X, Y;
            project(p, zscale, &X, &Y);
            fprintf(f, "%.1f,%.1f ", ox + (X - x0) * sc, oy + (Y - y0) * sc);
            zm += 0.25 * p[2];
        }
        q = (zm - zlo) / fmax(zhi - zlo, 1e-300);
        fprintf(f, "\" fill=\"rgb(%d,%d,%d)\"/>\n", (int)(60 + 190 * q),
                (int)(120 + 60 * (1 - fabs(2 * q - 1))), (int)(250 - 190 * q));
    }
    fprintf(f, "</g>\n<g fill=\"black\">\n");
    for (k = 0; k < gr->m * gr->n; k++) {
        double X, Y;
        project(gr->g + k * DIM, zscale, &X, &Y);
        fprintf(f, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"2.2\"/>\n", ox + (X - x0) * sc,
                oy + (Y - y0) * sc);
    }
    fprintf(
        f,
        "</g>\n<text x=\"10\" y=\"20\" font-family=\"sans-serif\" font-size=\"13\">"
        "bicubic B-spline surface through a %zu x %zu grid (dots), isometric view</text>\n</svg>\n",
        gr->m, gr->n);
    free(cells);
    return close_output(f, path);
}

/* Samples of surface s on steps per cell into smp (su x sv, sv = (n - 1) *
 * steps + 1) by forward differences patch by patch; shared edges are written
 * by both neighbours (the later one wins; they agree to rounding).  patch
 * holds (steps + 1)^2 points. */
static int sample(const surf_t *s, const grid_t *gr, size_t steps, size_t sv, double *patch,
                  double *smp)
{
    size_t i, j, a, b;
    for (i = 0; i + 1 < gr->m; i++)
        for (j = 0; j + 1 < gr->n; j++) {
            if (surf_patch_fd(s, i, j, (unsigned)steps, (unsigned)steps, patch) < 0)
                return -1;
            for (a = 0; a <= steps; a++)
                for (b = 0; b <= steps; b++)
                    memcpy(smp + ((i * steps + a) * sv + j * steps + b) * DIM,
                           patch + (a * (steps + 1) + b) * DIM, DIM * sizeof *smp);
        }
    /* Grid nodes exactly: the interpolation condition, not FD rounding. */
    for (i = 0; i < gr->m; i++)
        for (j = 0; j < gr->n; j++)
            memcpy(smp + ((i * steps) * sv + j * steps) * DIM, gr->g + (i * gr->n + j) * DIM,
                   DIM * sizeof *smp);
    return 0;
}

/* The samples CSV to path ("-": stdout); 0 or -1 with a message. */
static int write_samples(const char *path, const double *smp, size_t su, size_t sv, long steps)
{
    errno = 0;
    FILE *out = strcmp(path, "-") ? fopen(path, "w") : stdout;
    size_t a, b;
    if (!out) {
        fprintf(stderr, "%s: %s\n", path, strerror(errno));
        return -1;
    }
    fprintf(out, "u,v,x,y,z\n");
    for (a = 0; a < su; a++)
        for (b = 0; b < sv; b++) {
            const double *p = smp + (a * sv + b) * DIM;
            fprintf(out, "%.17g,%.17g,%.17g,%.17g,%.17g\n", (double)a / steps, (double)b / steps,
                    p[0], p[1], p[2]);
        }
    return close_output(out, out == stdout ? "stdout" : path);
}

static const struct option lopts[] = {
    {"steps", required_argument, NULL, 'n'},
    {"output", required_argument, NULL, 'o'},
    {"svg", required_argument, NULL, 's'},
    {"dx", required_argument, NULL, 'x'},
    {"dy", required_argument, NULL, 'y'},
    {"zscale", required_argument, NULL, 'z'},
    {"help", no_argument, NULL, 'h'},
    {"version", no_argument, NULL, 'V'},
    {NULL, 0, NULL, 0},
};

int main(int argc, char **argv)
{
    const char *out_path = "-", *svg_path = NULL;
    double dx = 1.0, dy = 1.0, zscale = 1.0;
    long steps = 8;
    grid_t gr = {0, 0, NULL};
    double *ctrl = NULL, *scratch = NULL, *smp = NULL, *patch = NULL;
    size_t su, sv;
    surf_t s;
    int opt, rc = 1;

    if (stdfds_open() < 0)
        return 71; /* EX_OSERR: no /dev/null */
    while ((opt = getopt_long(argc, argv, "n:o:s:x:y:z:hV", lopts, NULL)) != -1) {
        char *end = NULL;
        switch (opt) {
        case 'n': steps = strtol(optarg, &end, 10); break;
        case 'o': out_path = optarg; break;
        case 's': svg_path = optarg; break;
        case 'x': dx = strtod(optarg, &end); break;
        case 'y': dy = strtod(optarg, &end); break;
        case 'z': zscale = strtod(optarg, &end); break;
        case 'h': help(); return 0;
        case 'V': printf("trajsurf %s\n", TRAJD_VERSION); return 0;
        default: usage(stderr); return 2;
        }
        if (end && (*end || end == optarg)) {
            usage(stderr);
            return 2;
        }
    }
    if (optind != argc - 1 || steps < 1 || steps > SAMPLES_MAX || !(isfinite(dx) && dx > 0) ||
        !(isfinite(dy) && dy > 0) || !isfinite(zscale)) { /* a spacing of 0 collapses the grid */
        usage(stderr);
        return 2;
    }
    if (read_grid(argv[optind], dx, dy, &gr) < 0)
        goto out;
    ctrl = malloc((gr.m + 2) * (gr.n + 2) * DIM * sizeof *ctrl);
    scratch = malloc(surf_scratch_len(gr.m, gr.n, DIM) * sizeof *scratch);
    su = (gr.m - 1) * (size_t)steps + 1;
    sv = (gr.n - 1) * (size_t)steps + 1;
    smp = malloc(su * sv * DIM * sizeof *smp);
    patch = malloc((size_t)(steps + 1) * (size_t)(steps + 1) * DIM * sizeof *patch);
    if (!ctrl || !scratch || !smp || !patch) {
        fprintf(stderr, "trajsurf: out of memory\n");
        goto out;
    }
    if ((rc = surf_interpolate(gr.m, gr.n, DIM, gr.g, ctrl, scratch, &s)) < 0) {
        fprintf(stderr, "%s: %s\n", argv[optind], surf_strerror(rc));
        rc = 1;
        goto out;
    }
    rc = 1;
    if (sample(&s, &gr, (size_t)steps, sv, patch, smp) < 0)
        goto out;
    rc = 3; /* an output could not be written */
    if (write_samples(out_path, smp, su, sv, steps) < 0)
        goto out;
    if (svg_path && write_svg(svg_path, &gr, smp, su, sv, zscale) < 0)
        goto out;
    rc = 0;
out:
    free(gr.g);
    free(ctrl);
    free(scratch);
    free(smp);
    free(patch);
    return rc;
}
