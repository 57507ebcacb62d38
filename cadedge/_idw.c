/* Interior sizes for gmsh's size callback (cadedge/mesh/interior.py): the inverse-distance mean of the sizes
 * at a face's nearest curvature samples.
 *
 * gmsh calls the callback about 4 times per triangle, one point at a time; scipy's cKDTree took 43 us per
 * single-point query from Python, 10 to 15 s of the M6 screw's meshing at ALD 1e-3. A face has at most a few
 * hundred samples (cadedge.mesh.interior.SAMPLES squared), so a plain scan finds the nearest in a few us.
 */
#include "_kernels.h"

#define MAXNEAR 16

/* idw_size(points (m, 3) f64, sizes (m,) f64, x, y, z, k): the sizes of the k nearest points to (x, y, z)
 * weighted by 1 / (distance + 1e-12), summed nearest first (as numpy did with cKDTree's sorted answer). */
PyObject *ck_idw_size(PyObject *self, PyObject *args)
{
    Buffers b = {.n = 0};
    Py_ssize_t np_, ns;
    double q[3], kk;
    const double *pts = ck_arg(&b, args, 0, F64, 0, &np_);
    const double *sizes = ck_arg(&b, args, 1, F64, 0, &ns);
    if (!sizes || ck_num(args, 2, q) || ck_num(args, 3, q + 1) || ck_num(args, 4, q + 2) || ck_num(args, 5, &kk)) {
        ck_release(&b);
        return NULL;
    }
    Py_ssize_t m = ns, k = (Py_ssize_t)kk;
    if (np_ != 3 * m || k < 1 || k > MAXNEAR || k > m) {
        ck_release(&b);
        PyErr_SetString(PyExc_ValueError, "idw_size: mismatched shapes or k out of range");
        return NULL;
    }
    double best[MAXNEAR];
    Py_ssize_t at[MAXNEAR], have = 0;
    for (Py_ssize_t i = 0; i < m; i++) {
        double d = distance(q, 0, pts, i);
        if (have == k && !(d < best[k - 1]))
            continue;
        Py_ssize_t j = have < k ? have++ : k - 1; /* insertion into the sorted k nearest */
        while (j > 0 && best[j - 1] > d) {
            best[j] = best[j - 1];
            at[j] = at[j - 1];
            j--;
        }
        best[j] = d;
        at[j] = i;
    }
    double num = 0.0, den = 0.0;
    for (Py_ssize_t j = 0; j < k; j++) {
        double w = 1.0 / (best[j] + 1e-12);
        num += w * sizes[at[j]];
        den += w;
    }
    ck_release(&b);
    return PyFloat_FromDouble(num / den);
}
