"""The line-contact Hertz approach (flexgear.stiffness.hertz.hertz_approach and the contact
solver's kernel flexgear.dynamics.contact.laws.hertz_line) against Johnson's closed form and
against the elastic field it comes from.

K. L. Johnson, Contact Mechanics (Cambridge 1985), 2D Hertz contact of cylinders: half-width
a = sqrt(4 P R / (pi E*)), P = F / L, peak pressure p0 = 2 P / (pi a), and along the axis of
symmetry (McEwen) sigma_z = -p0 a / sqrt(a^2 + z^2), sigma_x = -(p0 / a) [(a^2 + 2 z^2) /
sqrt(a^2 + z^2) - 2 z]. In 2D the displacement is logarithmic, so an approach exists only between
datum points: body i is compressed between the surface at the centre of contact and the point
at depth d_i on the axis by

    delta_i = P (1 - nu_i^2) / (pi E_i) [2 ln(2 d_i / a) - nu_i / (1 - nu_i)]    (plane strain,
                                                                                d_i >> a),

(Johnson's plane-strain result for the approach in line contact, ch. 5), and the two surfaces
coincide at the centre, so the approach of the two datum points is delta_1 + delta_2. Checked
two ways: the package equals the closed form to round-off (dissimilar bodies and depths, so a
swapped material or depth is seen), and the closed form equals the integral of the
plane-strain strain along the axis to O((a/d)^2) (so the closed form as written here is the
elastic field's, not a copy of the code's).
"""
import math

import pytest
from scipy.integrate import quad

from flexgear.dynamics.contact.laws import hertz_line
from flexgear.gears.material import Material
from flexgear.stiffness.hertz import hertz_approach

STEEL = Material(E=2.1e11, nu=0.3, rho=7850.0)
BRONZE = Material(E=1.1e11, nu=0.34, rho=8800.0)
R, L = 6.0e-3, 0.02          # relative radius of curvature [m], contact length [m]
D1, D2 = 2.0e-3, 3.5e-3      # datum depths [m] (near-field depths of gear teeth)
LOADS = (200.0, 2.0e3, 1.0e4, 3.0e4)  # N; steel on bronze: a = 31 ... 377 um, d / a = 65 ... 5.3


def _e_star(m1, m2):
    return 1.0 / ((1 - m1.nu ** 2) / m1.E + (1 - m2.nu ** 2) / m2.E)


def _half_width(F, m1, m2):
    return math.sqrt(4.0 * (F / L) * R / (math.pi * _e_star(m1, m2)))


def johnson(F, m1, m2, d1, d2):
    """Johnson's plane-strain approach of the datum points at depths d1, d2 [m]."""
    P, a = F / L, _half_width(F, m1, m2)
    return sum(P * (1 - m.nu ** 2) / (math.pi * m.E) * (2 * math.log(2 * d / a) - m.nu / (1 - m.nu))
               for m, d in ((m1, d1), (m2, d2)))


def johnson_slope(F, m1, m2, d1, d2):
    """d(approach)/dF [m/N] of the closed form (a ~ sqrt(F): d/dF [F ln(1/a)] = ln(1/a) - 1/2)."""
    a = _half_width(F, m1, m2)
    return sum((1 - m.nu ** 2) / (math.pi * m.E * L) * (2 * math.log(2 * d / a) - 1 - m.nu / (1 - m.nu))
               for m, d in ((m1, d1), (m2, d2)))


def axis_compression(F, m, d, a):
    """Compression [m] of a body between the contact centre and depth d: the integral of the
    plane-strain normal strain -eps_z = -[(1 - nu^2) sigma_z - nu (1 + nu) sigma_x] / E along the
    axis under the Hertz pressure of half-width a."""
    p0 = 2 * (F / L) / (math.pi * a)

    def strain(z):
        r = math.sqrt(a * a + z * z)
        sz = -p0 * a / r
        sx = -p0 * a ** 3 / (r * (a * a + 2 * z * z + 2 * z * r))  # (a^2 + 2 z^2)/r - 2 z, without cancellation
        return -((1 - m.nu ** 2) * sz - m.nu * (1 + m.nu) * sx) / m.E

    val, _ = quad(strain, 0.0, d, limit=200, epsabs=0.0, epsrel=1e-12)
    return val


def _kernel_args(m1, m2, d1, d2):
    def k_nu(m):  # 1/(pi E1), nu1 of plane strain, from E and nu directly
        return (1 - m.nu ** 2) / (math.pi * m.E), m.nu / (1 - m.nu)
    ka, na = k_nu(m1)
    kb, nb = k_nu(m2)
    return (R, L, ka, na, d1, kb, nb, d2, _e_star(m1, m2))


@pytest.mark.parametrize("F", LOADS)
@pytest.mark.parametrize("m1, m2", [(STEEL, STEEL), (STEEL, BRONZE), (BRONZE, STEEL)], ids=["st-st", "st-br", "br-st"])
def test_hertz_approach_is_johnsons_closed_form(F, m1, m2):
    """Both implementations equal Johnson's plane-strain approach to round-off (1e-10), at
    four loads over two decades, for equal and dissimilar bodies and unequal depths; the
    kernel's compliance equals the closed form's slope."""
    ref = johnson(F, m1, m2, D1, D2)
    assert hertz_approach(F, R, L, m1, m2, D1, D2, "plane_strain") == pytest.approx(ref, rel=1e-10, abs=0.0)
    h, dh = hertz_line(F, *_kernel_args(m1, m2, D1, D2))
    assert h == pytest.approx(ref, rel=1e-10, abs=0.0)
    assert dh == pytest.approx(johnson_slope(F, m1, m2, D1, D2), rel=1e-10, abs=0.0)


@pytest.mark.parametrize("F", LOADS)
def test_closed_form_is_the_integral_of_the_strain_on_the_axis(F):
    """Johnson's closed form is the compression of the elastic half-plane field between the
    surface and the datum depth: the quadrature of the axis strain equals it up to its
    neglected terms, [(1 - nu^2)/4 + nu (1 + nu)/8] (a/d)^2 against (1 - nu^2) ln(2 d/a) in the
    bracket, bounded here by (a/d)^2 / ln(2 d/a) of the approach (1.5 % at d/a = 5.3, 30 kN;
    the difference is 0.24 % there and 8e-6 at 200 N)."""
    m1, m2 = STEEL, BRONZE
    a = _half_width(F, m1, m2)
    exact = axis_compression(F, m1, D1, a) + axis_compression(F, m2, D2, a)
    ref = johnson(F, m1, m2, D1, D2)
    d = min(D1, D2)
    assert abs(exact - ref) <= (a / d) ** 2 / math.log(2 * d / a) * ref
    # the package against the field itself, at the deep datum where the closed form is exact
    # to 1e-5 of the approach: a 0.5 % change of the approach fails by 500 x the bar
    deep1, deep2 = 300 * a, 400 * a
    field = axis_compression(F, m1, deep1, a) + axis_compression(F, m2, deep2, a)
    assert hertz_approach(F, R, L, m1, m2, deep1, deep2) == pytest.approx(field, rel=1e-5, abs=0.0)
    assert hertz_line(F, *_kernel_args(m1, m2, deep1, deep2))[0] == pytest.approx(field, rel=1e-5, abs=0.0)


def test_load_dependence_is_logarithmic():
    """delta / F grows as -ln(a) ~ -ln(F) / 2: between F and 100 F the compliance falls by
    ln(10) sum_i 2 / (pi E1_i L) per newton (Johnson: line contact stiffens with load, but
    slower than any power law); checked on the kernel."""
    args = _kernel_args(STEEL, BRONZE, D1, D2)
    F = 500.0
    drop = hertz_line(F, *args)[0] / F - hertz_line(100 * F, *args)[0] / (100 * F)
    expected = math.log(10.0) * sum(2 * (1 - m.nu ** 2) / (math.pi * m.E * L) for m in (STEEL, BRONZE))
    assert drop == pytest.approx(expected, rel=1e-10, abs=0.0)
