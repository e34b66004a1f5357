"""Contact detection on hand-checkable configurations of the real outlines."""
import math

import numpy as np
import pytest

from flexgear.gears.sdf import build_sdf
from flexgear.gears.contact_tables import candidate_teeth, pack_gears
from flexgear.dynamics.contact.search import MeshPair, mesh_contacts
from flexgear.dynamics.contact.field import PlacedField, sdf_lookup
from flexgear.gears.geometry import GearPair, SpurGear

M = 2e-3


def gears(thin=0.0):
    sun = SpurGear(24, M, bore_diameter=0.02, thinning=thin, name="sun")
    pl = SpurGear(21, M, bore_diameter=0.02, thinning=thin, name="planet")
    ring = SpurGear(66, M, internal=True, rim_diameter=0.16, ha=0.85, thinning=thin, name="ring")
    return sun, pl, ring


@pytest.fixture(scope="module")
def tables():
    sun, pl, ring = gears()
    return (sun, pl, ring), pack_gears([sun, pl, ring])


def contacts(T, ia, ib, internal, pa, pb, gA, gB, a):
    out_f = np.zeros((8, 5))
    out_i = np.zeros((8, 3), np.int64)
    pair = MeshPair(ia, ib, internal, candidate_teeth(gA, gB, a, internal), candidate_teeth(gB, gA, a, internal), 16, 0.0)
    n = mesh_contacts(np.asarray(pa, float), np.asarray(pb, float), pair, T, out_f, out_i)
    return out_f[:n].copy(), out_i[:n].copy()


@pytest.mark.parametrize("internal", [False, True])
def test_sdf_is_the_signed_distance_near_the_flanks(internal):
    """Points offset by +-delta along the flank normal have SDF = +-delta (the band where
    contact happens); the sign is right everywhere in the tooth band."""
    g = (SpurGear(66, M, internal=True, rim_diameter=0.16, ha=0.85) if internal
         else SpurGear(24, M, bore_diameter=0.02))
    s = build_sdf(g)
    field = PlacedField(s.grid[None], s.r0, s.dr, s.phi0, s.dphi, s.pitch, s.internal, s.z, 0.0, 0.0, 0.0, g.ra,
                        np.zeros(s.z, np.int64), np.zeros(s.z))
    o = g.tooth_outline(ds=M / 400)
    k = o.kind
    flank = [i for i in range(30, len(k) - 30) if np.all(k[i - 30:i + 31] == 2)]  # away from the corners
    rng = np.random.default_rng(1)
    errs = []
    for i in rng.choice(flank, 60):
        p, q = o.points[i - 1], o.points[i + 1]
        t = (q - p) / np.hypot(*(q - p))
        n_out = np.array([t[1], -t[0]])  # CCW outline of an external gear: outward normal on the right
        if internal:
            n_out = -n_out  # material outside the outline
        for delta in (-40e-6, -5e-6, 5e-6, 40e-6):
            x, y = o.points[i] + delta * n_out
            f, nx, ny, tooth, side = sdf_lookup(field, x, y)
            errs.append(abs(f - delta))
            assert tooth == 0
            assert np.dot([nx, ny], n_out) > 0.999  # the gradient is the outward normal
    assert max(errs) < 20e-9
    # sign everywhere in the band (against the generated half-tooth angle)
    for _ in range(300):
        r = rng.uniform(min(g.rf, g.ra), max(g.rf, g.ra))
        phi = rng.uniform(-math.pi, math.pi)
        f, *_ = sdf_lookup(field, r * math.cos(phi), r * math.sin(phi))
        rel = math.atan2(math.sin(phi * g.z), math.cos(phi * g.z)) / g.z
        in_tooth = abs(rel) < g.half_angle(r)
        if abs(abs(rel) - g.half_angle(r)) * r > 2e-6:
            assert (f < 0) == in_tooth


# centred positions (zero backlash): A at the origin, B at (a, 0)
def centred_external(gA, gB, a, thA):
    phi_a = (gA.z * thA / (2 * math.pi)) % 1.0
    return math.pi + 2 * math.pi * (0.5 - phi_a) / gB.z


@pytest.mark.parametrize("pair", ["sun-planet", "planet-ring"])
def test_penetration_equals_base_circle_arc_over_a_mesh_cycle(tables, pair):
    """Involute contact: turning the driver by dtheta from the centred (zero-backlash) position
    makes every loaded tooth pair penetrate by r_b dtheta along the line of action, wherever the
    pair is on its path of contact; the number of pairs follows the contact ratio."""
    (sun, pl, ring), T = tables
    a = 0.045
    counts = []
    for k in range(120):
        s = k / 120 * 2 * math.pi / (sun.z if pair == "sun-planet" else pl.z)
        if pair == "sun-planet":
            thA = s
            thB = centred_external(sun, pl, a, thA)
            d = 3e-6
            cf, ci = contacts(T, 0, 1, False, [0, 0, thA + d / sun.rb], [a, 0, thB], sun, pl, a)
            gA = sun
        else:
            # planet at (a, 0) inside the ring; planet tooth facing the ring space at angle 0
            thR = 0.0
            phi_r = ((ring.z * (thR - 0.0)) / (2 * math.pi)) % 1.0
            thP0 = 2 * math.pi * (phi_r + 0.5) / pl.z
            thP = thP0 + s
            thR = s * pl.z / ring.z  # rolling keeps the centred position
            d = 3e-6
            cf, ci = contacts(T, 1, 2, True, [a, 0, thP + d / pl.rb], [0, 0, thR], pl, ring, a)
            gA = pl
        del gA
        assert len(cf) >= 1
        assert len(set(map(tuple, ci[:, 2:3]))) == 1  # all on the same flank side
        # contacts on the line of action (involute-involute) penetrate by exactly r_b dtheta;
        # others are corner contacts of a tooth just past the end of its path (tip contact)
        gA_ = sun if pair == "sun-planet" else pl
        gB_ = pl if pair == "sun-planet" else ring
        cA = np.array([0.0, 0.0]) if pair == "sun-planet" else np.array([a, 0.0])
        cB = np.array([a, 0.0]) if pair == "sun-planet" else np.array([0.0, 0.0])
        on_loa = []
        for c in cf:
            r = math.hypot(c[1] - cA[0], c[2] - cA[1])
            rB = math.hypot(c[1] - cB[0], c[2] - cB[1])
            exact = abs(c[0] - d) < 15e-9
            corner = abs(r - gA_.ra) < 60e-6 or abs(rB - gB_.ra) < 60e-6  # within 3 samples of a tip
            assert exact or corner, (c, r, rB)
            on_loa.append(exact)
        counts.append(int(np.sum(on_loa)))
    eps = GearPair(sun, pl).contact_ratio if pair == "sun-planet" else GearPair(pl, ring).contact_ratio
    # fraction of the cycle with two pairs in contact = eps - 1
    two = np.mean(np.array(counts) == 2)
    assert set(counts) <= {1, 2}
    assert two == pytest.approx(eps - 1, abs=3 / 120)


def test_backlash_and_back_flank_contact():
    """With tooth thinning t on both gears the normal backlash is j_bn = 2 t cos(alpha); from
    the centred position each flank has j_bn/2 play. Turning the driver forward closes the
    drive flanks, backward closes the back flanks (other side), each after r_b dtheta = j_bn/2."""
    t = 50e-6
    sun, pl, _ = gears(thin=t)
    T = pack_gears([sun, pl])
    a = 0.045
    jbn = 2 * t * math.cos(sun.pressure_angle)
    thB = centred_external(sun, pl, a, 0.0)
    cf, _ = contacts(T, 0, 1, False, [0, 0, 0.0], [a, 0, thB], sun, pl, a)
    assert len(cf) == 0  # free play: no contact in the centred position
    for sense in (1, -1):
        # just before closing: no contact; beyond: penetration = r_b dtheta - j_bn / 2
        cf, _ = contacts(T, 0, 1, False, [0, 0, sense * 0.99 * jbn / 2 / sun.rb], [a, 0, thB], sun, pl, a)
        assert len(cf) == 0
        extra = 2e-6
        cf, ci = contacts(T, 0, 1, False, [0, 0, sense * (jbn / 2 + extra) / sun.rb], [a, 0, thB], sun, pl, a)
        assert len(cf) >= 1
        np.testing.assert_allclose(cf[:, 0], extra, atol=20e-9)
        assert np.all(ci[:, 2] == sense)  # forward: left flanks of the sun; backward: right flanks
        # the force on the sun opposes its rotation
        moment = cf[:, 1] * cf[:, 4] - cf[:, 2] * cf[:, 3]
        assert np.all(np.sign(moment) == -sense)


def test_tip_contact_off_the_line_of_action():
    """Past the end of the path of contact, a sun tooth whose flanks no longer touch is turned
    further into the planet: the contact is at the sun's tip corner (radius r_a), off the line of
    action, with the normal of the planet's flank there, not the line of action's direction."""
    sun, pl, _ = gears()
    T = pack_gears([sun, pl])
    a = 0.045
    pair = GearPair(sun, pl)
    # rotate the pair so that a sun tooth is beyond the end of its path of contact and
    # push the planet back (reduce the planet angle) until the tip touches
    ga = pair.path_of_contact[1]
    found = False
    for k in range(60):
        thA = k / 60 * 2 * math.pi / sun.z
        thB = centred_external(sun, pl, a, thA)
        cf, ci = contacts(T, 0, 1, False, [0, 0, thA + 20e-6 / sun.rb], [a, 0, thB], sun, pl, a)
        for c in cf:
            r = math.hypot(c[1], c[2])
            if abs(r - sun.ra) < 3 * M / 100:
                # a corner contact: not on the line of action (the LOA is tangent to the base circles)
                loa = np.array([math.sin(pair.alpha_w), math.cos(pair.alpha_w)])
                n = c[3:5]
                ang = math.degrees(math.acos(min(1.0, abs(n @ loa))))
                if ang > 1.0:
                    found = True
                    assert c[0] > 0
    del ga
    assert found, "no tip-corner contact found in a mesh cycle with 20 um transmission error"


def test_candidate_band_misses_no_contact(tables):
    """Searching only the candidate band of teeth finds exactly the contacts that a search over
    half of each gear finds, over a mesh cycle with a transmission error (incl. corner contacts)."""
    (sun, pl, ring), T = tables
    a = 0.045

    def search(pa, pb, ia, ib, internal, nA, nB):
        out_f = np.zeros((8, 5))
        out_i = np.zeros((8, 3), np.int64)
        n = mesh_contacts(np.asarray(pa, float), np.asarray(pb, float), MeshPair(ia, ib, internal, nA, nB, 16, 0.0), T,
                          out_f, out_i)
        return sorted((tuple(out_i[i]), round(out_f[i, 0], 12)) for i in range(n))

    for gA, gB, ia, ib, internal in ((sun, pl, 0, 1, False), (pl, ring, 1, 2, True)):
        nA, nB = candidate_teeth(gA, gB, a, internal), candidate_teeth(gB, gA, a, internal)
        assert 1 <= nA < gA.z // 4 and 1 <= nB < gB.z // 4  # a real restriction
        for k in range(40):
            s = k / 40 * 2 * math.pi / gA.z
            if internal:
                thA = 2 * math.pi * 0.5 / pl.z + s + 20e-6 / pl.rb
                pa, pb = [a, 0, thA], [0, 0, s * pl.z / ring.z]
            else:
                pa, pb = [0, 0, s + 20e-6 / sun.rb], [a, 0, centred_external(sun, pl, a, s)]
            band = search(pa, pb, ia, ib, internal, nA, nB)
            assert band, k
            assert band == search(pa, pb, ia, ib, internal, gA.z // 2, gB.z // 2)
