"""A bracketing root finder, so the tests need no SciPy."""


def bisect(f, a, b, tol=1e-15, iterations=200):
    """A root of f in [a, b] (f(a), f(b) of opposite signs) by bisection to `tol`."""
    fa = f(a)
    for _ in range(iterations):
        m = 0.5 * (a + b)
        fm = f(m)
        if (fm < 0) == (fa < 0):
            a, fa = m, fm
        else:
            b = m
        if b - a < tol:
            break
    return 0.5 * (a + b)
