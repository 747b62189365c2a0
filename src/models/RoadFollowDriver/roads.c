/* Test roads for the road-follow driver (roads.h). */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "roads.h"

static int fail(char *err, size_t errlen, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    if (err && errlen) vsnprintf(err, errlen, fmt, ap);
    va_end(ap);
    return -1;
}

double road_wrap(double a) {
    a = fmod(a + M_PI, 2 * M_PI);
    if (a <= 0) a += 2 * M_PI;
    return a - M_PI;
}

/* ---- built-in roads ---------------------------------------------------------- */

/* A road y(x) along +x made of pieces: each moves y from y0 to y1 over
 * [x0, x0 + len] along half a cosine period (constant y if y0 == y1). */
typedef struct { double x0, len, y0, y1; } Piece;

static double piece_y(const Piece *p, int np, double x) {
    for (int i = 0; i < np; i++) {
        if (x <= p[i].x0 + p[i].len || i == np - 1) {
            const double u = fmin(fmax((x - p[i].x0) / p[i].len, 0.0), 1.0);
            return p[i].y0 + (p[i].y1 - p[i].y0) * 0.5 * (1.0 - cos(M_PI * u));
        }
    }
    return 0.0;
}

static int profile(const Piece *p, int np, double step, double *x, double *y, int cap,
                   char *err, size_t errlen) {
    const double end = p[np - 1].x0 + p[np - 1].len;
    const int m = road_int(ceil(end / step - 1e-9));
    if (m + 1 > cap)
        return fail(err, errlen, "road of %.6g m needs %d points at step %.6g m, more than %d",
                    end, m + 1, step, cap);
    for (int k = 0; k <= m; k++) {
        x[k] = k < m ? k * step : end;
        y[k] = piece_y(p, np, x[k]);
    }
    return m + 1;
}

/* lane change: half a cosine period over laneLength with lateral offset
 * laneOffset, straights before and after (seed 001, ch. 4: 3.25 m; 25 m at
 * 50 km/h, 60 m at 100 km/h) */
static int lane_change(const RoadParams *q, double *x, double *y, int cap, char *err, size_t errlen) {
    const Piece p[] = {
        { 0.0, q->before, 0.0, 0.0 },
        { q->before, q->laneLength, 0.0, q->laneOffset },
        { q->before + q->laneLength, q->after, q->laneOffset, q->laneOffset },
    };
    return profile(p, 3, q->step, x, y, cap, err, errlen);
}

/* ISO 3888-1 double lane change (ISO 3888-1:2018 "Passenger cars - Test track
 * for a severe lane-change manoeuvre - Part 1: Double lane-change", Fig. 1 and
 * Table 1): section 1 entry lane 15 m long, 1.1 b + 0.25 m wide; section 2
 * 30 m; section 3 side lane 25 m long, b + 1 m wide, offset 3.5 m; section 4
 * 25 m; section 5 exit lane 15 m (b vehicle width). Our reading of the figure:
 * the 3.5 m offset is between the right-hand boundaries of lanes 1 and 3, so
 * the side lane's centre line lies 3.5 + ((b + 1) - (1.1 b + 0.25)) / 2 m to
 * the left; the exit lane is centred on the entry lane's centre line. The
 * standard fixes the cones, not the path: our centre line changes lane along
 * half a cosine period over the whole of sections 2 and 4. */
static int iso3888(const RoadParams *q, double *x, double *y, int cap, char *err, size_t errlen) {
    const double b = q->isoWidth;
    const double w1 = 1.1 * b + 0.25, w3 = b + 1.0;
    const double y3 = 3.5 + (w3 - w1) / 2;
    const double x1 = q->before, x2 = x1 + 15, x3 = x2 + 30, x4 = x3 + 25, x5 = x4 + 25, x6 = x5 + 15;
    const Piece p[] = {
        { 0.0, x2, 0.0, 0.0 },       /* straight before and section 1 */
        { x2, 30.0, 0.0, y3 },       /* section 2 */
        { x3, 25.0, y3, y3 },        /* section 3 */
        { x4, 25.0, y3, 0.0 },       /* section 4 */
        { x5, 15.0 + q->after, 0.0, 0.0 },   /* section 5 and straight after */
    };
    (void)x1; (void)x6;
    return profile(p, 5, q->step, x, y, cap, err, errlen);
}

/* full circle of radius |R| (seed 000: 17.5 m), entered from a straight along
 * +x and left to the same straight after 360 deg */
static int circle(const RoadParams *q, double *x, double *y, int cap, char *err, size_t errlen) {
    const double R = q->R, h = q->step;
    const int nb = road_int(ceil(q->before / h - 1e-9));
    const int nc = road_int(ceil(2 * M_PI * fabs(R) / h - 1e-9));
    const int na = road_int(ceil(q->after / h - 1e-9));
    const long long n = (long long)nb + nc + na + 1;
    if (n > cap)
        return fail(err, errlen, "circle road needs %lld points at step %.6g m, more than %d", n, h, cap);
    int k = 0;
    for (int i = 0; i < nb; i++, k++) { x[k] = q->before * i / nb; y[k] = 0.0; }
    for (int i = 0; i < nc; i++, k++) {
        const double phi = (R > 0 ? 2 : -2) * M_PI * i / nc;   /* heading along the circle */
        x[k] = q->before + R * sin(phi);
        y[k] = R * (1.0 - cos(phi));
    }
    for (int i = 0; i <= na; i++, k++) { x[k] = q->before + (na ? q->after * i / na : 0.0); y[k] = 0.0; }
    return k;
}

int road_generate(int kind, const RoadParams *q, double *x, double *y, int cap,
                  char *err, size_t errlen) {
    if (!(q->step > 0))
        return fail(err, errlen, "road step = %g m must be > 0", q->step);
    if (!(q->before >= 0) || !(q->after >= 0))
        return fail(err, errlen, "straights before = %g m and after = %g m must be >= 0",
                    q->before, q->after);
    switch (kind) {
    case ROAD_LANE_CHANGE:
        if (!(q->laneLength > 0))
            return fail(err, errlen, "laneLength = %g m must be > 0", q->laneLength);
        if (!isfinite(q->laneOffset))
            return fail(err, errlen, "laneOffset = %g m must be finite", q->laneOffset);
        return lane_change(q, x, y, cap, err, errlen);
    case ROAD_CIRCLE:
        if (!(fabs(q->R) >= 1.0) || !isfinite(q->R))
            return fail(err, errlen, "circle radius R = %g m: |R| must be >= 1 m", q->R);
        return circle(q, x, y, cap, err, errlen);
    case ROAD_ISO3888:
        if (!(q->isoWidth > 0))
            return fail(err, errlen, "isoWidth = %g m must be > 0", q->isoWidth);
        return iso3888(q, x, y, cap, err, errlen);
    default:
        return fail(err, errlen, "road = %d is not a built-in road (1 lane change, 2 circle, "
                                 "3 ISO 3888-1)", kind);
    }
}

/* ---- CSV roads ----------------------------------------------------------------- */

static const char *skip_sep(const char *p) {
    while (*p == ' ' || *p == '\t' || *p == ',' || *p == ';' || *p == '\r' || *p == '\n') p++;
    return p;
}

/* a decimal number: strtod also takes hex floats (0x1p3), refused here as
   everywhere in artibus (inf and nan are read, then refused as not finite
   with their own message); *end = p if none */
static double decimal(const char *p, char **end) {
    const double v = strtod(p, end);
    for (const char *q = p; q < *end; q++)
        if (*q == 'x' || *q == 'X') {
            *end = (char *)p;
            return 0.0;
        }
    return v;
}

int road_read_csv(const char *path, double *x, double *y, int cap, char *err, size_t errlen) {
    FILE *f = fopen(path, "r");
    if (!f) return fail(err, errlen, "road file '%s': cannot open: %s", path, strerror(errno));
    char line[ROAD_LINE_MAX + 2];     /* the characters, the newline, the terminator */
    int n = 0, lineno = 0, prevline = 0, content = 0;
    while (fgets(line, sizeof line, f)) {
        lineno++;
        /* a line longer than the buffer is refused, never split (its tail would
           be read as a line of its own) */
        if (!strchr(line, '\n') && !feof(f)) {
            fclose(f);
            return fail(err, errlen, "road file '%s', line %d: longer than %d characters (the "
                                     "reader's limit)", path, lineno, ROAD_LINE_MAX);
        }
        char *hash = strchr(line, '#');
        if (hash) *hash = '\0';
        const char *p = skip_sep(line);
        if (!*p) continue;
        content++;
        char *end;
        const double xv = decimal(p, &end);
        const int xok = end != p;
        p = skip_sep(end);
        const double yv = xok ? decimal(p, &end) : 0.0;
        const int yok = xok && end != p;
        if (!yok) {
            if (content == 1) continue;          /* a header line */
            line[strcspn(line, "\r\n")] = '\0';
            fclose(f);
            return fail(err, errlen, "road file '%s', line %d: '%s' is not a point 'x,y'",
                        path, lineno, line);
        }
        if (*skip_sep(end)) {
            line[strcspn(line, "\r\n")] = '\0';
            fclose(f);
            return fail(err, errlen, "road file '%s', line %d: '%s' has more than two values "
                                     "(expected 'x,y')", path, lineno, line);
        }
        if (!isfinite(xv) || !isfinite(yv)) {
            fclose(f);
            return fail(err, errlen, "road file '%s', line %d: %s = %g is not a finite number",
                        path, lineno, isfinite(xv) ? "y" : "x", isfinite(xv) ? yv : xv);
        }
        if (n > 0 && xv == x[n - 1] && yv == y[n - 1]) {
            fclose(f);
            return fail(err, errlen, "road file '%s', line %d: point (%.17g, %.17g) repeats the "
                                     "point of line %d", path, lineno, xv, yv, prevline);
        }
        if (n >= cap) {
            fclose(f);
            return fail(err, errlen, "road file '%s', line %d: more than %d points", path, lineno, cap);
        }
        x[n] = xv;
        y[n] = yv;
        n++;
        prevline = lineno;
    }
    const int bad = ferror(f);
    fclose(f);
    if (bad) return fail(err, errlen, "road file '%s': read error after line %d", path, lineno);
    if (n < 2)
        return fail(err, errlen, "road file '%s': %d point(s) in %d line(s), at least 2 are needed",
                    path, n, lineno);
    return n;
}

/* ---- resampling by arc length ------------------------------------------------ */

int road_resample(const double *x, const double *y, int n, double ds, Road *r,
                  char *err, size_t errlen) {
    if (n < 2) return fail(err, errlen, "road has %d point(s), at least 2 are needed", n);
    if (!(ds > 0)) return fail(err, errlen, "resampling step ds = %g m must be > 0", ds);
    double length = 0.0;
    for (int j = 0; j + 1 < n; j++) {
        const double l = hypot(x[j + 1] - x[j], y[j + 1] - y[j]);
        if (!(l > 0))
            return fail(err, errlen, "road points %d and %d coincide at (%.17g, %.17g)",
                        j, j + 1, x[j], y[j]);
        length += l;
    }
    const int m = road_int(ceil(length / ds - 1e-9));
    if (m + 1 > ROAD_MAX_POINTS)
        return fail(err, errlen, "road of %.6g m at ds = %g m needs %d points, more than the "
                                 "table's %d", length, ds, m + 1, ROAD_MAX_POINTS);
    r->n = m + 1;
    r->ds = ds;
    r->length = length;
    int j = 0;
    double sj = 0.0, lj = hypot(x[1] - x[0], y[1] - y[0]);   /* segment j: [sj, sj + lj] */
    for (int k = 0; k <= m; k++) {
        const double s = k < m ? k * ds : length;
        while (j + 2 < n && s > sj + lj) {
            sj += lj;
            j++;
            lj = hypot(x[j + 1] - x[j], y[j + 1] - y[j]);
        }
        const double u = fmin(fmax((s - sj) / lj, 0.0), 1.0);
        r->s[k] = s;
        r->x[k] = x[j] + u * (x[j + 1] - x[j]);
        r->y[k] = y[j] + u * (y[j + 1] - y[j]);
    }
    /* tangent: central differences, one-sided at the ends */
    for (int k = 0; k < r->n; k++) {
        const int a = k > 0 ? k - 1 : 0, b = k + 1 < r->n ? k + 1 : r->n - 1;
        r->psi[k] = atan2(r->y[b] - r->y[a], r->x[b] - r->x[a]);
    }
    return 0;
}

/* ---- look-up ----------------------------------------------------------------- */

int road_index(const Road *r, double s) {
    if (!(s > 0)) return 0;
    const int i = road_int(s / r->ds + 0.5);
    return i < r->n ? i : r->n - 1;
}

/* foot of (px, py) on segment a..a+1; t is free beyond the road's ends */
static double foot_on(const Road *r, int a, double px, double py, RoadFoot *f) {
    const double ex = r->x[a + 1] - r->x[a], ey = r->y[a + 1] - r->y[a];
    const double l2 = ex * ex + ey * ey, l = sqrt(l2);
    double t = ((px - r->x[a]) * ex + (py - r->y[a]) * ey) / l2;
    if (t < 0 && a > 0) t = 0;
    if (t > 1 && a + 2 < r->n) t = 1;
    f->x = r->x[a] + t * ex;
    f->y = r->y[a] + t * ey;
    f->s = r->s[a] + t * l;
    const double u = fmin(fmax(t, 0.0), 1.0);
    f->psi = road_wrap(r->psi[a] + u * road_wrap(r->psi[a + 1] - r->psi[a]));
    f->eLat = (ex * (py - r->y[a]) - ey * (px - r->x[a])) / l;
    f->i = t < 0.5 ? a : a + 1;
    return hypot(px - f->x, py - f->y);
}

RoadFoot road_project(const Road *r, double px, double py, int lo, int hi) {
    if (lo < 0) lo = 0;
    if (hi > r->n - 1) hi = r->n - 1;
    if (lo > hi) lo = hi;
    int best = lo;
    double dbest = INFINITY;
    for (int i = lo; i <= hi; i++) {
        const double d = (r->x[i] - px) * (r->x[i] - px) + (r->y[i] - py) * (r->y[i] - py);
        if (d < dbest) { dbest = d; best = i; }
    }
    RoadFoot f, g;
    const int a = best > 0 ? best - 1 : 0;
    double d = foot_on(r, a, px, py, &f);
    if (best > 0 && best + 1 < r->n) {
        const double e = foot_on(r, best, px, py, &g);
        if (e < d) f = g;
    }
    return f;
}
