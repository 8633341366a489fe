"""Mean and Student-t 95 % confidence interval, and Welch's t-test, without scipy (as mapc-sim's metrics.rs)."""
import math


def _betacf(a, b, x):
    """Continued fraction of the regularised incomplete beta function (modified Lentz)."""
    tiny = 1e-300
    qab, qap, qam = a + b, a + 1.0, a - 1.0
    c, d = 1.0, 1.0 - qab * x / qap
    d = 1.0 / (d if abs(d) > tiny else tiny)
    h = d
    for m in range(1, 300):
        m2 = 2 * m
        aa = m * (b - m) * x / ((qam + m2) * (a + m2))
        d = 1.0 + aa * d
        d = 1.0 / (d if abs(d) > tiny else tiny)
        c = 1.0 + aa / c if abs(1.0 + aa / c) > tiny else tiny
        h *= d * c
        aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2))
        d = 1.0 + aa * d
        d = 1.0 / (d if abs(d) > tiny else tiny)
        c = 1.0 + aa / c if abs(1.0 + aa / c) > tiny else tiny
        delta = d * c
        h *= delta
        if abs(delta - 1.0) < 1e-15:
            break
    return h


def _betainc(a, b, x):
    if x <= 0.0:
        return 0.0
    if x >= 1.0:
        return 1.0
    lbeta = math.lgamma(a + b) - math.lgamma(a) - math.lgamma(b)
    front = math.exp(lbeta + a * math.log(x) + b * math.log(1.0 - x))
    if x < (a + 1.0) / (a + b + 2.0):
        return front * _betacf(a, b, x) / a
    return 1.0 - front * _betacf(b, a, 1.0 - x) / b


def t_cdf(t, dof):
    x = dof / (dof + t * t)
    tail = 0.5 * _betainc(dof / 2.0, 0.5, x)
    return 1.0 - tail if t > 0 else tail


def t_quantile_975(dof):
    lo, hi = 0.0, 50.0
    for _ in range(200):
        mid = (lo + hi) / 2.0
        if t_cdf(mid, dof) < 0.975:
            lo = mid
        else:
            hi = mid
    return (lo + hi) / 2.0


def mean_ci(xs):
    """(mean, half-width of the 95 % CI, standard deviation)."""
    n = len(xs)
    m = sum(xs) / n
    if n < 2:
        return m, float("nan"), 0.0
    sd = math.sqrt(sum((x - m) ** 2 for x in xs) / (n - 1))
    return m, t_quantile_975(n - 1) * sd / math.sqrt(n), sd


def sd_from_ci(ci95, n):
    """The standard deviation behind a Student-t 95 % half-width over n runs (mapc's JSON gives the half-width)."""
    return ci95 * math.sqrt(n) / t_quantile_975(n - 1)


def welch(ma, sda, na, mb, sdb, nb):
    """Welch's t statistic and two-sided p-value of ma - mb, from means, standard deviations and counts."""
    va, vb = sda ** 2, sdb ** 2
    se2 = va / na + vb / nb
    # Identical runs (the I-696 window's inflow: the whole demand enters every time) have no spread to test.
    if se2 <= 1e-12 * max(1.0, ma * ma, mb * mb):
        return float("inf") if ma != mb else 0.0, 0.0 if ma != mb else 1.0
    t = (ma - mb) / math.sqrt(se2)
    dof = se2 ** 2 / ((va / na) ** 2 / (na - 1) + (vb / nb) ** 2 / (nb - 1))
    return t, 2.0 * (1.0 - t_cdf(abs(t), dof))
