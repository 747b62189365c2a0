/* Test roads for the road-follow driver: the built-in parametric roads, CSV
 * roads (x, y), and their resampling by arc length into a fixed-size table.
 * Plain C, no FMI types; the step never allocates: roads are built once, at
 * initialisation. The same file is loaded by src/artibus/roads.py (ctypes),
 * so Python draws exactly the road the FMU follows.
 *
 * Coordinates in m, angles in rad. Built-in roads start at (0, 0) heading
 * along +x.
 */
#ifndef ROADS_H
#define ROADS_H

#include <stddef.h>

#define ROAD_MAX_POINTS 20000    /* resampled table: 2 km at ds = 0.1 m */
#define ROAD_RAW_MAX    200000   /* points of a generated or CSV polyline */

/* a count or an index from a double, range-checked: NaN -> 0, clamped to
 * +-1e9 (beyond every table, within int), so huge distances give "too many
 * points" or the table's end instead of an undefined conversion */
static inline int road_int(double x) {
    return x != x ? 0 : x > 1e9 ? 1000000000 : x < -1e9 ? -1000000000 : (int)x;
}
#define ROAD_ERRLEN     512
#define ROAD_LINE_MAX   4096     /* characters of a CSV line (a longer one is refused) */

enum { ROAD_CSV = 0, ROAD_LANE_CHANGE = 1, ROAD_CIRCLE = 2, ROAD_ISO3888 = 3 };

/* parameters of the built-in roads (ROAD_CSV uses none of them) */
typedef struct {
    double before;       /* straight before the manoeuvre [m] */
    double after;        /* straight after the manoeuvre [m] */
    double laneLength;   /* lane change: length of the half cosine period [m] */
    double laneOffset;   /* lane change: lateral offset, > 0 to the left [m] */
    double R;            /* circle: radius, > 0 turns left, < 0 right [m] */
    double isoWidth;     /* ISO 3888-1: vehicle width b, sets the lane widths [m] */
    double step;         /* spacing of the generated polyline [m] */
} RoadParams;

/* the road resampled by arc length: point k at s[k] = k * ds (the last at the
 * end of the road), psi[k] the tangent direction, wrapped to (-pi, pi] */
typedef struct {
    int n;
    double ds, length;
    double s[ROAD_MAX_POINTS], x[ROAD_MAX_POINTS], y[ROAD_MAX_POINTS], psi[ROAD_MAX_POINTS];
} Road;

/* nearest point of the road to a point: arc length s, the foot point, the
 * tangent there, the signed lateral offset (> 0 left of the road) and the
 * index of the table point nearest to the foot */
typedef struct {
    double s, x, y, psi, eLat;
    int i;
} RoadFoot;

/* A built-in road as a polyline into x[], y[] (capacity cap). Returns the
 * number of points, or -1 with a message in err. */
int road_generate(int kind, const RoadParams *p, double *x, double *y, int cap,
                  char *err, size_t errlen);

/* A CSV road: one "x,y" per line (also ';', tab or blanks), '#' comments and
 * a non-numeric first line (header) allowed. Refuses NaN/Inf, repeated
 * consecutive points, fewer than 2 points. Returns the number of points, or
 * -1 with a message naming the file, the line and the value. */
int road_read_csv(const char *path, double *x, double *y, int cap, char *err, size_t errlen);

/* Resample the polyline by arc length at spacing ds into r. Returns 0, or -1
 * with a message (too long for the table, repeated points, < 2 points). */
int road_resample(const double *x, const double *y, int n, double ds, Road *r,
                  char *err, size_t errlen);

/* Nearest point to (px, py) among table points lo..hi (clamped to the road),
 * refined on the segments either side; beyond the ends the road continues as
 * a straight line along its first/last segment. O(hi - lo). */
RoadFoot road_project(const Road *r, double px, double py, int lo, int hi);

/* index of the table point at arc length s (clamped) */
int road_index(const Road *r, double s);

/* angle wrapped to (-pi, pi] */
double road_wrap(double a);

#endif
