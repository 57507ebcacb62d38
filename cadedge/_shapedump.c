/* OCCT's binary B-rep stream (BinTools_ShapeSet::Write, format versions 2-4) read in one call.
 *
 * Reading a shape's topology and its edges' geometry from Python costs one OCP call (0.5-1 us) per
 * item: per edge some 30 of them. OCCT writes the whole shape in one C++ call, exactly (IEEE doubles,
 * little-endian); here that stream is parsed (cadedge/occt/shapedump.py drives both):
 *
 *   - the curves (BinTools_CurveSet's layout) as rows of the geometry table of cadedge/_batch.c;
 *   - every TShape: type, sub-shapes with orientation; a vertex's point and tolerance; an edge's tolerance,
 *     degenerate flag and first 3-D curve representation (curve index and range);
 *   - the topology in TopExp::MapShapes order, which is public (ids): a depth-first walk from the root
 *     numbers faces, edges and vertices at their first visit, as TopExp_Explorer does.
 *
 * 2-D curves and surfaces are only skipped (their layout fixes their size). A stream this reader does not
 * take (locations, triangulations or polygons, an unknown type, a size that does not add up) raises
 * ValueError: the caller then reads the shape through OCP instead, never from a guess. The layouts are
 * those of OCCT's BinTools_ShapeSet.cxx, BinTools_CurveSet.cxx, BinTools_Curve2dSet.cxx and
 * BinTools_SurfaceSet.cxx (the same in OCCT 7.6-8.0).
 */
#include <stdlib.h>
#include <string.h>

#include "_kernels.h"

enum { LINE = 0, CONIC = 1, SPLINE = 2, SKIPPED = -1 };
enum { BT_LINE = 1, BT_CIRCLE, BT_ELLIPSE, BT_PARABOLA, BT_HYPERBOLA, BT_BEZIER, BT_BSPLINE, BT_TRIMMED, BT_OFFSET };
enum { S_PLANE = 1, S_CYLINDER, S_CONE, S_SPHERE, S_TORUS, S_EXTRUSION, S_REVOLUTION, S_BEZIER, S_BSPLINE,
       S_RECTANGULAR, S_OFFSET };
enum { COMPOUND = 0, COMPSOLID, SOLID, SHELL, FACE, WIRE, EDGE, VERTEX };
#define MAX_DEPTH 64 /* nesting of trimmed/offset curves and surfaces */

typedef struct {
    const unsigned char *d;
    Py_ssize_t size, pos;
    const char *error; /* the first reason the stream was refused */
} Reader;

typedef struct {
    double *d;
    Py_ssize_t n, cap;
} Vec;

static int push(Vec *v, const double *x, Py_ssize_t k)
{
    if (v->n + k > v->cap) {
        Py_ssize_t cap = v->cap ? v->cap : 256;
        while (cap < v->n + k)
            cap *= 2;
        double *d = realloc(v->d, cap * sizeof(double));
        if (!d)
            return -1;
        v->d = d, v->cap = cap;
    }
    memcpy(v->d + v->n, x, k * sizeof(double));
    v->n += k;
    return 0;
}

static PyObject *as_bytes(const void *data, Py_ssize_t size) { return PyByteArray_FromStringAndSize(data, size); }

/* Little-endian reads (BinTools fixes that byte order on every machine); 0 after a failed need(). */
static int need(Reader *r, Py_ssize_t k)
{
    if (k < 0 || r->pos + k > r->size) {
        if (!r->error)
            r->error = "the stream ends inside an item";
        return 0;
    }
    return 1;
}

static uint64_t le(const unsigned char *p, int size)
{
    uint64_t v = 0;
    for (int k = size - 1; k >= 0; k--)
        v = (v << 8) | p[k];
    return v;
}

static double le_double(const unsigned char *p)
{
    uint64_t bits = le(p, 8);
    double x;
    memcpy(&x, &bits, 8);
    return x;
}

static int u8(Reader *r) { return need(r, 1) ? r->d[r->pos++] : -1; }
static long u16(Reader *r) { return need(r, 2) ? (long)le(r->d + (r->pos += 2) - 2, 2) : -1; }
static long i32(Reader *r) { return need(r, 4) ? (long)(int32_t)le(r->d + (r->pos += 4) - 4, 4) : 0; }
static double f64(Reader *r) { return need(r, 8) ? le_double(r->d + (r->pos += 8) - 8) : 0.0; }
static int skip(Reader *r, Py_ssize_t k) { return need(r, k) ? (r->pos += k, 1) : 0; }

static int fail(Reader *r, const char *why)
{
    if (!r->error)
        r->error = why;
    return 0;
}

/* A section header "<name> <count>\n"; the count, or -1. */
static Py_ssize_t header(Reader *r, const char *name)
{
    size_t len = strlen(name);
    if (r->pos + (Py_ssize_t)len + 2 > r->size || memcmp(r->d + r->pos, name, len) || r->d[r->pos + len] != ' ') {
        fail(r, "a section header is not where the layout puts it");
        return -1;
    }
    r->pos += len + 1;
    Py_ssize_t count = 0, digits = 0;
    while (r->pos < r->size && r->d[r->pos] >= '0' && r->d[r->pos] <= '9' && digits < 10)
        count = 10 * count + (r->d[r->pos++] - '0'), digits++;
    if (!digits || r->pos >= r->size || r->d[r->pos] != '\n') {
        fail(r, "a section header has no count");
        return -1;
    }
    r->pos++;
    return count;
}

/* A spline's poles, weights and knots: n poles of dim doubles (+ a weight if rational), nk (knot, mult). */
static int skip_spline(Reader *r, long n, long nk, int dim, int rational)
{
    if (n < 1 || nk < 0)
        return fail(r, "a spline has no poles");
    return skip(r, (Py_ssize_t)n * 8 * (dim + rational) + (Py_ssize_t)nk * 12);
}

static int skip_curve2d(Reader *r, int depth)
{
    int type = u8(r), rational;
    long degree;
    if (depth > MAX_DEPTH)
        return fail(r, "curves nested too deep");
    switch (type) {
    case BT_LINE: return skip(r, 4 * 8);
    case BT_CIRCLE: case BT_PARABOLA: return skip(r, 7 * 8);
    case BT_ELLIPSE: case BT_HYPERBOLA: return skip(r, 8 * 8);
    case BT_BEZIER:
        rational = u8(r), degree = u16(r);
        return rational >= 0 && degree >= 0 && skip_spline(r, degree + 1, 0, 2, rational != 0);
    case BT_BSPLINE: {
        rational = u8(r), u8(r), degree = u16(r);
        long n = i32(r), nk = i32(r);
        return rational >= 0 && degree >= 0 && skip_spline(r, n, nk, 2, rational != 0);
    }
    case BT_TRIMMED: return skip(r, 2 * 8) && skip_curve2d(r, depth + 1);
    case BT_OFFSET: return skip(r, 8) && skip_curve2d(r, depth + 1);
    default: return fail(r, "a 2-D curve of unknown type");
    }
}

static int skip_curve3d(Reader *r, int depth)
{
    int type = u8(r), rational;
    long degree;
    if (depth > MAX_DEPTH)
        return fail(r, "curves nested too deep");
    switch (type) {
    case BT_LINE: return skip(r, 6 * 8);
    case BT_CIRCLE: case BT_PARABOLA: return skip(r, 13 * 8);
    case BT_ELLIPSE: case BT_HYPERBOLA: return skip(r, 14 * 8);
    case BT_BEZIER:
        rational = u8(r), degree = u16(r);
        return rational >= 0 && degree >= 0 && skip_spline(r, degree + 1, 0, 3, rational != 0);
    case BT_BSPLINE: {
        rational = u8(r), u8(r), degree = u16(r);
        long n = i32(r), nk = i32(r);
        return rational >= 0 && degree >= 0 && skip_spline(r, n, nk, 3, rational != 0);
    }
    case BT_TRIMMED: return skip(r, 2 * 8) && skip_curve3d(r, depth + 1);
    case BT_OFFSET: return skip(r, 4 * 8) && skip_curve3d(r, depth + 1);
    default: return fail(r, "a curve of unknown type");
    }
}

static int skip_surface(Reader *r, int depth)
{
    int type = u8(r);
    if (depth > MAX_DEPTH)
        return fail(r, "surfaces nested too deep");
    switch (type) {
    case S_PLANE: return skip(r, 12 * 8);
    case S_CYLINDER: case S_SPHERE: return skip(r, 13 * 8);
    case S_CONE: case S_TORUS: return skip(r, 14 * 8);
    case S_EXTRUSION: return skip(r, 3 * 8) && skip_curve3d(r, 0);
    case S_REVOLUTION: return skip(r, 6 * 8) && skip_curve3d(r, 0);
    case S_BEZIER: {
        int ur = u8(r), vr = u8(r);
        long ud = u16(r), vd = u16(r);
        return ur >= 0 && vr >= 0 && ud >= 0 && vd >= 0 && skip_spline(r, (ud + 1) * (vd + 1), 0, 3, ur || vr);
    }
    case S_BSPLINE: {
        int ur = u8(r), vr = u8(r);
        u8(r), u8(r);
        long ud = u16(r), vd = u16(r), nu = i32(r), nv = i32(r), nku = i32(r), nkv = i32(r);
        return ur >= 0 && vr >= 0 && ud >= 0 && vd >= 0 && nu > 0 && nv > 0 &&
               skip_spline(r, nu * nv, nku + nkv, 3, ur || vr);
    }
    case S_RECTANGULAR: return skip(r, 4 * 8) && skip_surface(r, depth + 1);
    case S_OFFSET: return skip(r, 8) && skip_surface(r, depth + 1);
    default: return fail(r, "a surface of unknown type");
    }
}

/* One curve as a geometry table row (cadedge/_batch.c): meta = (kind, degree, knots, dim, periodic, type);
 * kind SKIPPED for the types the table does not evaluate (parabola, hyperbola, trimmed, offset). */
static int parse_curve(Reader *r, int64_t *m, Vec *out)
{
    Py_ssize_t at = r->pos;
    int type = u8(r);
    m[5] = type;
    if (type == BT_LINE) {
        double v[6];
        if (!need(r, 48))
            return 0;
        for (int k = 0; k < 6; k++)
            v[k] = f64(r);
        m[0] = LINE;
        return push(out, v, 6) < 0 ? -1 : 1;
    }
    if (type == BT_CIRCLE || type == BT_ELLIPSE) {
        int radii = type == BT_CIRCLE ? 1 : 2;
        double v[11]; /* location, (axis skipped), X direction, Y direction, radii */
        if (!need(r, 96 + 8 * radii))
            return 0;
        const unsigned char *p = r->d + r->pos;
        for (int k = 0; k < 3; k++)
            v[k] = le_double(p + 8 * k);
        for (int k = 3; k < 9; k++)
            v[k] = le_double(p + 8 * (k + 3));
        v[9] = le_double(p + 96);
        v[10] = radii == 2 ? le_double(p + 104) : v[9];
        r->pos += 96 + 8 * radii;
        m[0] = CONIC;
        return push(out, v, 11) < 0 ? -1 : 1;
    }
    if (type == BT_BEZIER || type == BT_BSPLINE) {
        int spline = type == BT_BSPLINE;
        int rational = u8(r) > 0;
        m[4] = spline ? u8(r) > 0 : 0;
        long degree = u16(r);
        long n = degree + 1, nk = 0;
        if (spline)
            n = i32(r), nk = i32(r);
        if (r->error || degree < 0 || n < 1 || nk < 0)
            return fail(r, "a spline has no poles");
        Py_ssize_t dim = rational ? 4 : 3;
        if (!need(r, (Py_ssize_t)n * 8 * dim + (Py_ssize_t)nk * 12))
            return 0;
        const unsigned char *p = r->d + r->pos;
        double nan = NAN;
        if (push(out, &nan, 1) < 0)
            return -1;
        Py_ssize_t knots = 0;
        if (spline) {
            const unsigned char *kp = p + n * 8 * dim;
            for (Py_ssize_t k = 0; k < nk; k++) {
                double knot = le_double(kp + 12 * k);
                int32_t mult = (int32_t)le(kp + 12 * k + 8, 4);
                for (int32_t j = 0; j < mult; j++)
                    if (push(out, &knot, 1) < 0)
                        return -1;
                knots += mult > 0 ? mult : 0;
            }
        } else {
            double ends[2] = {0.0, 1.0};
            for (int e = 0; e < 2; e++)
                for (long j = 0; j <= degree; j++)
                    if (push(out, ends + e, 1) < 0)
                        return -1;
            knots = 2 * (degree + 1);
        }
        for (Py_ssize_t i = 0; i < n; i++) {
            double v[4];
            for (int k = 0; k < dim; k++)
                v[k] = le_double(p + 8 * (dim * i + k));
            if (rational)
                v[0] *= v[3], v[1] *= v[3], v[2] *= v[3];
            if (push(out, v, dim) < 0)
                return -1;
        }
        r->pos += n * 8 * dim + nk * 12;
        m[0] = SPLINE, m[1] = degree, m[2] = knots, m[3] = dim;
        return 1;
    }
    r->pos = at;
    m[0] = SKIPPED;
    return skip_curve3d(r, 0);
}

/* count curves from r->pos into meta (count x 6), offsets (count + 1), out; 1, 0 (refused) or -1 (memory). */
static int parse_curves_at(Reader *r, Py_ssize_t count, int64_t *meta, int64_t *offsets, Vec *out)
{
    offsets[0] = 0;
    for (Py_ssize_t c = 0; c < count; c++) {
        int ok = parse_curve(r, meta + 6 * c, out);
        if (ok <= 0)
            return ok;
        offsets[c + 1] = out->n;
    }
    return 1;
}

static PyObject *refused(Reader *r, const char *where)
{
    PyErr_Format(PyExc_ValueError, "%s: %s (at byte %zd)", where, r->error ? r->error : "refused", r->pos);
    return NULL;
}

/* parse_curves(data, start, count) -> (meta, offsets, numbers, end): the count curves that
 * BinTools_CurveSet::Write put in data from byte start, as geometry table rows (bytearrays of int64,
 * int64, float64; see parse_curve), and the byte after them. */
PyObject *ck_parse_curves(PyObject *self, PyObject *args)
{
    Py_buffer buf;
    Py_ssize_t start, count;
    if (!PyArg_ParseTuple(args, "y*nn", &buf, &start, &count))
        return NULL;
    Reader r = {buf.buf, buf.len, start, NULL};
    PyObject *result = NULL;
    int64_t *meta = calloc(6 * count + 1, sizeof(int64_t)), *offsets = calloc(count + 1, sizeof(int64_t));
    Vec out = {0};
    int ok = meta && offsets && start >= 0 ? parse_curves_at(&r, count, meta, offsets, &out) : -1;
    if (ok < 0)
        PyErr_NoMemory();
    else if (ok == 0)
        refused(&r, "parse_curves");
    else
        result = Py_BuildValue("(NNNn)", as_bytes(meta, 6 * count * 8), as_bytes(offsets, (count + 1) * 8),
                               as_bytes(out.d, out.n * 8), r.pos);
    free(meta), free(offsets), free(out.d);
    PyBuffer_Release(&buf);
    return result;
}

/* ---------------------------------------------------------------- shapes */

static const char *VERSIONS[] = {"Open CASCADE Topology V2 (c)", "Open CASCADE Topology V3 (c)",
                                 "Open CASCADE Topology V4, (c) Open Cascade"};

typedef struct {
    Py_ssize_t n;           /* TShapes */
    uint8_t *type;          /* per TShape */
    int64_t *sub_ofs;       /* sub-shapes of TShape s: sub[sub_ofs[s]:sub_ofs[s + 1]] (0-based TShape) */
    int64_t *sub;
    uint8_t *sub_ori;
    double *real;           /* per TShape: vertex (tolerance, x, y, z); edge (tolerance, first, last) */
    int64_t *curve;         /* edge: index of its first 3-D curve (1-based), 0 if none; degenerate flag */
    uint8_t *degenerate;
} Shapes;

/* The TShapes section; 1, 0 (refused) or -1 (memory). */
static int parse_tshapes(Reader *r, Shapes *s, int version)
{
    Py_ssize_t n = s->n, cap = 4 * n + 16, count = 0;
    s->type = calloc(n + 1, 1), s->sub_ori = malloc(cap), s->degenerate = calloc(n + 1, 1);
    s->sub_ofs = calloc(n + 1, sizeof(int64_t)), s->sub = malloc(cap * sizeof(int64_t));
    s->real = calloc(4 * n + 1, sizeof(double)), s->curve = calloc(n + 1, sizeof(int64_t));
    if (!s->type || !s->sub_ori || !s->degenerate || !s->sub_ofs || !s->sub || !s->real || !s->curve)
        return -1;
    for (Py_ssize_t i = 0; i < n; i++) {
        int type = u8(r);
        if (type < COMPOUND || type > VERTEX)
            return fail(r, "a shape of unknown type");
        s->type[i] = (uint8_t)type;
        double *real = s->real + 4 * i;
        if (type == VERTEX) {
            for (int k = 0; k < 4; k++)
                real[k] = f64(r); /* tolerance (BRep_Tool::Tolerance), point */
            for (int rep; (rep = u8(r)) != 0;) {
                if (rep == 1 || rep == 2)
                    skip(r, rep == 1 ? 12 : 16);
                else if (rep == 3)
                    skip(r, 20);
                else
                    return fail(r, "a vertex representation of unknown type");
                if (i32(r) != 0)
                    return fail(r, "a located vertex representation");
            }
        } else if (type == EDGE) {
            double tol = f64(r);
            real[0] = tol > 1e-7 ? tol : 1e-7; /* BRep_Tool::Tolerance: at least Precision::Confusion() */
            u8(r), u8(r);
            s->degenerate[i] = u8(r) > 0;
            for (int rep; (rep = u8(r)) != 0;) {
                long loc = 0;
                if (rep == 1) {
                    long c = i32(r);
                    loc = i32(r);
                    double first = f64(r), last = f64(r);
                    if (!s->curve[i])
                        s->curve[i] = c, real[1] = first, real[2] = last;
                } else if (rep == 2 || rep == 3) {
                    skip(r, rep == 2 ? 8 : 13);
                    loc = i32(r);
                    skip(r, 16 + (version < 4 ? 32 : 0));
                } else if (rep == 4) {
                    skip(r, 5), loc = i32(r), skip(r, 4);
                    loc |= i32(r);
                } else
                    return fail(r, "an edge representation this reader does not take (a polygon?)");
                if (loc != 0)
                    return fail(r, "a located edge representation");
            }
        } else if (type == FACE) {
            skip(r, 13);
            if (i32(r) != 0)
                return fail(r, "a located face surface");
            int tri = u8(r);
            if (tri == 2)
                skip(r, 4);
            else if (tri != 0 && tri != 1)
                return fail(r, "a face's triangulation flag is unknown");
        }
        skip(r, 7); /* flags: free, modified, checked, orientable, closed, infinite, convex */
        s->sub_ofs[i] = count;
        for (int ori; (ori = u8(r)) != '*';) {
            if (ori < 0 || ori > 3)
                return fail(r, "a sub-shape's orientation is unknown");
            long index = i32(r);
            if (i32(r) != 0)
                return fail(r, "a located sub-shape");
            index = n - index; /* written as nbShapes - index + 1; 0-based here */
            if (index < 0 || index >= i)
                return fail(r, "a sub-shape index out of range");
            if (count == cap) {
                cap *= 2;
                int64_t *sub = realloc(s->sub, cap * sizeof(int64_t));
                uint8_t *sub_ori = sub ? realloc(s->sub_ori, cap) : NULL;
                if (sub)
                    s->sub = sub;
                if (!sub || !sub_ori)
                    return -1;
                s->sub_ori = sub_ori;
            }
            s->sub[count] = index, s->sub_ori[count++] = (uint8_t)ori;
        }
        if (r->error)
            return 0;
    }
    s->sub_ofs[n] = count;
    return 1;
}

/* TopAbs::Compose(parent, child) */
static uint8_t compose(uint8_t parent, uint8_t child)
{
    static const uint8_t table[4][4] = {{0, 1, 2, 3}, {1, 0, 2, 3}, {2, 2, 2, 2}, {3, 3, 3, 3}};
    return table[child][parent];
}

/* Ids in MapShapes order: a depth-first walk from root numbering faces, edges and vertices (id[s], 1-based)
 * at their first visit, with the orientation they have there (ori), and every TShape's orientation as the
 * shape set stores it (stored: the raw one at its first visit); a subtree walked to its end is not walked
 * again (it holds nothing new). order[0], [1], [2] list the faces', edges' and vertices' TShapes by id. */
static int walk(const Shapes *s, Py_ssize_t root, uint8_t root_ori, int64_t *id, uint8_t *ori, uint8_t *stored,
                int64_t **order, Py_ssize_t *count)
{
    Py_ssize_t n = s->n, top = 0;
    int64_t *node = malloc((n + 1) * sizeof(int64_t)), *next = malloc((n + 1) * sizeof(int64_t));
    uint8_t *node_ori = malloc(n + 1), *node_raw = malloc(n + 1), *done = calloc(n + 1, 1), *seen = calloc(n + 1, 1);
    if (!node || !next || !node_ori || !node_raw || !done || !seen) {
        free(node), free(next), free(node_ori), free(node_raw), free(done), free(seen);
        return -1;
    }
    node[0] = root, next[0] = s->sub_ofs[root], node_ori[0] = node_raw[0] = root_ori;
    for (;;) {
        if (next[top] == s->sub_ofs[node[top]]) { /* first step into this node: a visit */
            Py_ssize_t t = node[top];
            int type = s->type[t];
            if (!seen[t]) /* as stored by BinTools_ShapeSet::Add, which meets the shapes in this order */
                seen[t] = 1, stored[t] = node_raw[top];
            int slot = type == FACE ? 0 : type == EDGE ? 1 : type == VERTEX ? 2 : -1;
            if (slot >= 0 && !id[t]) {
                order[slot][count[slot]] = t;
                id[t] = ++count[slot];
                ori[t] = node_ori[top];
            }
        }
        if (next[top] < s->sub_ofs[node[top] + 1]) {
            Py_ssize_t k = next[top]++, child = s->sub[k];
            if (!done[child]) {
                if (top + 1 > n) /* deeper than there are shapes: a cycle */
                    break;
                node_ori[top + 1] = compose(node_ori[top], s->sub_ori[k]);
                node_raw[top + 1] = s->sub_ori[k];
                node[++top] = child, next[top] = s->sub_ofs[child];
            }
            continue;
        }
        done[node[top]] = 1;
        if (top-- == 0)
            break;
    }
    int ok = top < 0;
    free(node), free(next), free(node_ori), free(node_raw), free(done), free(seen);
    return ok;
}

/* Record face f (1-based) on every edge under TShape t: counting (fids NULL: fofs[e + 1]++) or filling
 * (fids[fofs[e]++] = f); seen[e] == f marks an edge already recorded for this face. */
static int face_edges(const Shapes *s, Py_ssize_t t, int64_t f, const int64_t *id, int64_t *seen, int64_t *fofs,
                      int64_t *fids, int depth)
{
    if (depth > MAX_DEPTH)
        return 0;
    for (Py_ssize_t k = s->sub_ofs[t]; k < s->sub_ofs[t + 1]; k++) {
        Py_ssize_t c = s->sub[k];
        if (s->type[c] == EDGE) {
            Py_ssize_t e = id[c] - 1;
            if (e >= 0 && seen[e] != f) {
                seen[e] = f;
                if (fids)
                    fids[fofs[e]++] = f;
                else
                    fofs[e + 1]++;
            }
        } else if (s->type[c] < EDGE && !face_edges(s, c, f, id, seen, fofs, fids, depth + 1))
            return 0;
    }
    return 1;
}

/* parse_shapes(data, root, root_orientation) -> (curve_meta, curve_offsets, curve_numbers,
 *     edges, edge_real, face_offsets, edge_face_ids, vertices, vertex_real, faces, orientations)
 * data is BinTools_ShapeSet::Write's output (without triangulations) and root the shape set's 1-based index
 * of the root shape. In MapShapes order, edge e (0-based) is TShape edges[e, 0] (1-based, for
 * BinTools_ShapeSet::Shape), with curve index edges[e, 1] (1-based row of the curve arrays, 0 if none),
 * vertex ids edges[e, 2:4] (first, last; 0 if missing), degenerate flag edges[e, 4]; edge_real[e] is
 * (tolerance, first, last); its face ids are edge_face_ids[face_offsets[e]:face_offsets[e + 1]]
 * (increasing). vertices[v] is its TShape, vertex_real[v] (tolerance, x, y, z); faces[f] its TShape.
 * orientations[k] is the orientation at first visit of the TShape k + 1 (faces, edges and vertices), and
 * orientations[n + k] the one BinTools_ShapeSet::Shape(k + 1) has (n TShapes). */
PyObject *ck_parse_shapes(PyObject *self, PyObject *args)
{
    Py_buffer buf;
    Py_ssize_t root;
    int root_ori;
    if (!PyArg_ParseTuple(args, "y*ni", &buf, &root, &root_ori))
        return NULL;
    Reader r = {buf.buf, buf.len, 0, NULL};
    PyObject *result = NULL;
    Shapes s = {0};
    int64_t *meta = NULL, *offsets = NULL, *id = NULL, *order[3] = {NULL, NULL, NULL}, *edges = NULL;
    int64_t *fofs = NULL, *fids = NULL;
    double *ereal = NULL, *vreal = NULL;
    uint8_t *ori = NULL;
    Vec out = {0};
    Py_ssize_t ncurves = 0, count[3] = {0, 0, 0};
    int ok = 0, version = 0;
    /* "\n<version>\n" */
    if (r.size < 2 || r.d[0] != '\n')
        goto refuse;
    for (int v = 0; v < 3; v++) {
        size_t len = strlen(VERSIONS[v]);
        if ((Py_ssize_t)len + 2 <= r.size && !memcmp(r.d + 1, VERSIONS[v], len) && r.d[len + 1] == '\n')
            version = v + 2, r.pos = len + 2;
    }
    if (!version) {
        fail(&r, "not a BinTools shape stream of version 2, 3 or 4");
        goto refuse;
    }
    if (header(&r, "Locations") != 0) {
        fail(&r, "the shape has locations");
        goto refuse;
    }
    Py_ssize_t k2 = header(&r, "Curve2ds");
    for (Py_ssize_t c = 0; c < k2 && !r.error; c++)
        skip_curve2d(&r, 0);
    if (r.error || (ncurves = header(&r, "Curves")) < 0)
        goto refuse;
    meta = calloc(6 * ncurves + 1, sizeof(int64_t)), offsets = calloc(ncurves + 1, sizeof(int64_t));
    if (!meta || !offsets)
        goto nomem;
    if ((ok = parse_curves_at(&r, ncurves, meta, offsets, &out)) <= 0)
        goto end;
    if (header(&r, "Polygon3D") != 0 || header(&r, "PolygonOnTriangulations") != 0) {
        fail(&r, "the shape set holds polygons");
        goto refuse;
    }
    Py_ssize_t ns = header(&r, "Surfaces");
    for (Py_ssize_t c = 0; c < ns && !r.error; c++)
        skip_surface(&r, 0);
    if (r.error)
        goto refuse;
    if (header(&r, "Triangulations") != 0) {
        fail(&r, "the shape set holds triangulations");
        goto refuse;
    }
    if (r.pos >= r.size || r.d[r.pos++] != '\n' || (s.n = header(&r, "TShapes")) < 1)
        goto refuse;
    if ((ok = parse_tshapes(&r, &s, version)) <= 0)
        goto end;
    if (r.pos != r.size) {
        fail(&r, "bytes past the last shape");
        goto refuse;
    }
    if (root < 1 || root > s.n || root_ori < 0 || root_ori > 3) {
        fail(&r, "the root is not in the shape set");
        goto refuse;
    }
    id = calloc(s.n + 1, sizeof(int64_t)), ori = calloc(2 * s.n + 1, 1);
    for (int t = 0; t < 3; t++)
        order[t] = malloc((s.n + 1) * sizeof(int64_t));
    if (!id || !ori || !order[0] || !order[1] || !order[2])
        goto nomem;
    if ((ok = walk(&s, root - 1, (uint8_t)root_ori, id, ori, ori + s.n, order, count)) <= 0) {
        if (ok == 0)
            fail(&r, "the shapes contain a cycle");
        goto end;
    }
    Py_ssize_t nf = count[0], ne = count[1], nv = count[2];
    edges = calloc(5 * ne + 1, sizeof(int64_t)), ereal = calloc(3 * ne + 1, sizeof(double));
    vreal = calloc(4 * nv + 1, sizeof(double)), fofs = calloc(ne + 1, sizeof(int64_t));
    if (!edges || !ereal || !vreal || !fofs)
        goto nomem;
    for (Py_ssize_t e = 0; e < ne; e++) {
        Py_ssize_t t = order[1][e];
        int64_t *row = edges + 5 * e;
        row[0] = t + 1, row[1] = s.curve[t], row[4] = s.degenerate[t];
        if (row[1] < 0 || row[1] > ncurves) {
            fail(&r, "an edge's curve index is out of range");
            goto refuse;
        }
        for (int k = 0; k < 3; k++)
            ereal[3 * e + k] = s.real[4 * t + k];
        for (Py_ssize_t k = s.sub_ofs[t]; k < s.sub_ofs[t + 1]; k++) { /* TopExp::Vertices, the last one wins */
            Py_ssize_t v = s.sub[k];
            if (s.type[v] == VERTEX && s.sub_ori[k] <= 1)
                row[2 + s.sub_ori[k]] = id[v];
        }
    }
    for (Py_ssize_t v = 0; v < nv; v++)
        memcpy(vreal + 4 * v, s.real + 4 * order[2][v], 4 * sizeof(double));
    /* the faces of each edge: each face's edges (under its wires, or directly), faces in id order */
    int64_t *seen = calloc(ne + 1, sizeof(int64_t));
    if (!seen)
        goto nomem;
    for (int pass = 0; pass < 2 && ok > 0; pass++) {
        memset(seen, 0, (ne + 1) * sizeof(int64_t));
        for (Py_ssize_t f = 0; f < nf && ok > 0; f++)
            ok = face_edges(&s, order[0][f], f + 1, id, seen, fofs, pass ? fids : NULL, 0);
        if (pass == 0) {
            for (Py_ssize_t e = 0; e < ne; e++)
                fofs[e + 1] += fofs[e];
            if (!(fids = malloc((fofs[ne] + 1) * sizeof(int64_t))))
                ok = -1;
        }
    }
    free(seen);
    if (ok <= 0)
        goto end;
    for (Py_ssize_t e = ne; e > 0; e--) /* the fill advanced each start to the next one's */
        fofs[e] = fofs[e - 1];
    fofs[0] = 0;
    uint8_t *orient = malloc(2 * s.n + 1);
    if (!orient)
        goto nomem;
    memcpy(orient, ori, 2 * s.n);
    int64_t *faces = order[0], *verts = order[2];
    for (Py_ssize_t f = 0; f < nf; f++)
        faces[f] += 1;
    for (Py_ssize_t v = 0; v < nv; v++)
        verts[v] += 1;
    result = Py_BuildValue("(NNNNNNNNNNN)", as_bytes(meta, 6 * ncurves * 8), as_bytes(offsets, (ncurves + 1) * 8),
                           as_bytes(out.d, out.n * 8), as_bytes(edges, 5 * ne * 8), as_bytes(ereal, 3 * ne * 8),
                           as_bytes(fofs, (ne + 1) * 8), as_bytes(fids, fofs[ne] * 8), as_bytes(verts, nv * 8),
                           as_bytes(vreal, 4 * nv * 8), as_bytes(faces, nf * 8), as_bytes(orient, 2 * s.n));
    free(orient);
    goto end;
nomem:
    ok = -1;
    goto end;
refuse:
    ok = 0;
end:
    if (!result && ok < 0)
        PyErr_NoMemory();
    else if (!result && !PyErr_Occurred())
        refused(&r, "parse_shapes");
    free(meta), free(offsets), free(out.d), free(id), free(ori), free(edges), free(ereal), free(vreal);
    free(fofs), free(fids);
    for (int t = 0; t < 3; t++)
        free(order[t]);
    free(s.type), free(s.sub_ofs), free(s.sub), free(s.sub_ori), free(s.real), free(s.curve), free(s.degenerate);
    PyBuffer_Release(&buf);
    return result;
}
