"""HPDE Sec. 4.5: the arcs of the section planes and the DE start (Eq. 12-16), and the circle tangent."""
import numpy as np
import pytest

from meshlab_holefill.algorithms.xie_zou2013 import prediction as hpde_prediction

from hpde_cases import make_problem


# ----------------------------------------------------------------- step 5: Sec. 4.5

@pytest.mark.parametrize("theta", [-1.2, -0.3, 0.0, 1e-8, 0.5, np.pi / 2])
def test_arc_points_are_equally_spaced_on_a_circle_eq13(theta):
    L = 2.0
    s = np.linspace(0, 1, 8)[None, :]
    x, y = hpde_prediction.arc_points(np.array([theta]), np.array([L]), s)
    P = np.stack([x[0], y[0]], axis=1)
    assert np.allclose(P[0], 0) and np.allclose(P[-1], [L, 0])
    steps = np.linalg.norm(np.diff(P, axis=0), axis=1)
    assert np.allclose(steps, steps[0], rtol=1e-6)
    if abs(theta) > 1e-6:  # concyclic, tangent angle theta at the start
        R = L / (2 * np.sin(abs(theta)))
        center = np.array([L / 2, -np.sign(theta) * np.sqrt(max(R * R - L * L / 4, 0))])
        assert np.allclose(np.linalg.norm(P - center, axis=1), R)
        assert np.arctan2(P[1, 1], P[1, 0]) == pytest.approx(theta * (1 - 1 / 7), abs=1e-6)
    yh = hpde_prediction.arc_height(np.array([theta]), np.array([L]), x)
    assert np.allclose(yh, y, atol=1e-9)


def test_prediction_counts_eq15():
    lengths = np.array([1.0, 2.5, 4.0])
    m, M = hpde_prediction.prediction_counts(lengths, 0.5)
    assert M == 9
    assert m.tolist() == [int(np.floor(L / 4.0 * 9)) + 1 for L in lengths]


def test_eq12_x_average_and_eq16_start_between_the_arcs():
    problem, _ = make_problem(0.6, 0.2, 5)
    s = np.arange(1, 6) / 6
    xl, _ = hpde_prediction.arc_points(np.array([0.6]), np.array([3.0]), s[None])
    xu, _ = hpde_prediction.arc_points(np.array([0.2]), np.array([3.0]), s[None])
    assert np.allclose(problem.x[0], 0.5 * (xl + xu)[0])
    assert np.all(problem.lower <= problem.y_init + 1e-12) and np.all(problem.y_init <= problem.upper + 1e-12)
    # Eq. 16 starts on L_arc near P1 and moves to U_arc near P2.
    yl = hpde_prediction.arc_height(np.array([0.6]), np.array([3.0]), problem.x)[0]
    assert abs(problem.y_init[0, 0] - yl[0]) < abs(problem.y_init[0, -1] - yl[-1])


def test_angle_variation_is_zero_on_a_regular_chain():
    # Symmetric tangents: the chain AP, P1, PP.., P2, AP' of equal turning angles is a regular
    # polygon; its y-values make Eq. 14 vanish.
    m, L = 3, 2.0
    turn = 0.3
    # Regular polygon with m + 1 chords from P1 to P2: chord directions theta0 - i * turn.
    theta0 = turn * m / 2
    dirs = theta0 - turn * np.arange(m + 1)
    chord = L / np.cos(dirs).sum()
    pts = np.cumsum(chord * np.stack([np.cos(dirs), np.sin(dirs)], axis=1), axis=0)
    problem, _ = make_problem(theta0 + turn, theta0 + turn, m, L)
    problem.x[0] = pts[:m, 0]
    problem._chain = None
    f = hpde_prediction.angle_variation(problem, pts[None, None, :m, 1])
    assert f[0, 0] == pytest.approx(0.0, abs=1e-20)
    assert hpde_prediction.angle_variation(problem, pts[None, None, :m, 1] + 0.01)[0, 0] > 1e-6


def test_circle_start_angle_is_the_tangent_of_the_circle_through_ap():
    # On a circle the secant AP -> P_1 overshoots the tangent at P_1 by half the arc AP P_1:
    # the paper's literal arcs bulge outward (the sphere experiment's centre error).
    def on_circle(deg):
        return np.array([np.cos(np.radians(deg)), np.sin(np.radians(deg))])

    P1, P2, AP = on_circle(100), on_circle(30), on_circle(120)
    ex = (P2 - P1) / np.linalg.norm(P2 - P1)
    ey = np.array([-ex[1], ex[0]])
    ap = np.array([[(AP - P1) @ ex, (AP - P1) @ ey]])
    theta = hpde_prediction.circle_start_angle(ap, np.array([np.linalg.norm(P2 - P1)]))
    assert np.degrees(theta[0]) == pytest.approx(35.0)  # half of the 70-degree arc P_1 P_2
    secant = np.degrees(np.arctan2(-ap[0, 1], -ap[0, 0]))
    assert secant == pytest.approx(45.0)  # 35 + half of the 20-degree arc AP P_1
    # Collinear AP, P_1, P_2: a straight arc.
    assert hpde_prediction.circle_start_angle(np.array([[-0.5, 0.0]]), np.array([2.0]))[0] == 0.0


def test_circle_arcs_put_the_prediction_on_a_circle():
    # Section through a unit circle: AP, P_1, P_2, AP' on it; both 'circle' arcs are the circle
    # itself, so the bounds close and every x lies on it; the 'secant' arcs overshoot outward.
    ang = np.radians([130.0, 110.0, 30.0, 10.0])  # AP, P_1, P_2, AP'
    pts = np.stack([np.cos(ang), np.sin(ang), np.zeros(4)], axis=1)
    AP, P1, P2, AP2 = pts[:1], pts[1:2], pts[2:3], pts[3:4]
    Nv = np.array([[0, 0, 1.0]])
    circ, frames = hpde_prediction.section_problems(P1, P2, P1 - AP, AP2 - P2, Nv, np.array([5]), tangent="circle")
    sec, _ = hpde_prediction.section_problems(P1, P2, P1 - AP, AP2 - P2, Nv, np.array([5]))
    assert np.allclose(circ.lower, circ.upper, atol=1e-12)
    radius = lambda prob: np.linalg.norm(hpde_prediction.predicted_points(P1, frames, prob, prob.lower)[0],  # noqa: E731
                                         axis=1)
    assert np.allclose(radius(circ), 1.0, atol=1e-9)
    assert np.all(radius(sec) > 1.0 + 1e-3)
