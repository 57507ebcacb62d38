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
#include "_bintools.h"

enum { COMPOUND = 0, COMPSOLID, SOLID, SHELL, FACE, WIRE, EDGE, VERTEX };

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
    if (bt_header(&r, "Locations") != 0) {
        fail(&r, "the shape has locations");
        goto refuse;
    }
    Py_ssize_t k2 = bt_header(&r, "Curve2ds");
    for (Py_ssize_t c = 0; c < k2 && !r.error; c++)
        bt_skip_curve2d(&r, 0);
    if (r.error || (ncurves = bt_header(&r, "Curves")) < 0)
        goto refuse;
    meta = calloc(6 * ncurves + 1, sizeof(int64_t)), offsets = calloc(ncurves + 1, sizeof(int64_t));
    if (!meta || !offsets)
        goto nomem;
    if ((ok = bt_parse_curves_at(&r, ncurves, meta, offsets, &out)) <= 0)
        goto end;
    if (bt_header(&r, "Polygon3D") != 0 || bt_header(&r, "PolygonOnTriangulations") != 0) {
        fail(&r, "the shape set holds polygons");
        goto refuse;
    }
    Py_ssize_t ns = bt_header(&r, "Surfaces");
    for (Py_ssize_t c = 0; c < ns && !r.error; c++)
        bt_skip_surface(&r, 0);
    if (r.error)
        goto refuse;
    if (bt_header(&r, "Triangulations") != 0) {
        fail(&r, "the shape set holds triangulations");
        goto refuse;
    }
    if (r.pos >= r.size || r.d[r.pos++] != '\n' || (s.n = bt_header(&r, "TShapes")) < 1)
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
        bt_refused(&r, "parse_shapes");
    free(meta), free(offsets), free(out.d), free(id), free(ori), free(edges), free(ereal), free(vreal);
    free(fofs), free(fids);
    for (int t = 0; t < 3; t++)
        free(order[t]);
    free(s.type), free(s.sub_ofs), free(s.sub), free(s.sub_ori), free(s.real), free(s.curve), free(s.degenerate);
    PyBuffer_Release(&buf);
    return result;
}
