"""Models through the bindings: Jacobians against central differences, inverse(predict)."""
import numpy as np
import pytest

import seif


def numeric_jacobian(f, x, h=1e-6):
    x = np.asarray(x, dtype=float)
    cols = []
    for i in range(x.size):
        e = np.zeros_like(x)
        e[i] = h
        cols.append((np.asarray(f(x + e)) - np.asarray(f(x - e))) / (2 * h))
    return np.stack(cols, axis=1)


POSE = np.array([0.3, -0.2, 0.7])
LANDMARK = np.array([1.4, 0.9])


@pytest.mark.parametrize("sensor", [
    seif.RangeBearingModel(0.1, 0.05),
    seif.RangeBearingModel(0.1, 0.05, np.array([0.2, 0.1, 0.3])),
    seif.CartesianModel(np.diag([0.01, 0.02]), np.array([-0.1, 0.05, -0.2])),
])
def test_measurement_jacobians_and_inverse(sensor):
    z, J_x, J_y = sensor.predict(POSE, LANDMARK)
    assert J_x.shape == (2, 3) and J_y.shape == (2, 2)
    np.testing.assert_allclose(J_x, numeric_jacobian(lambda x: sensor.predict(x, LANDMARK)[0], POSE), atol=1e-7)
    np.testing.assert_allclose(J_y, numeric_jacobian(lambda y: sensor.predict(POSE, y)[0], LANDMARK), atol=1e-7)
    y, J_yx, J_yz = sensor.inverse(POSE, z)
    np.testing.assert_allclose(y, LANDMARK, atol=1e-12)
    np.testing.assert_allclose(J_yz, numeric_jacobian(lambda zz: sensor.inverse(POSE, zz)[0], z), atol=1e-7)
    np.testing.assert_allclose(J_yx, numeric_jacobian(lambda x: sensor.inverse(x, z)[0], POSE), atol=1e-7)
    np.testing.assert_allclose(sensor.residual(z, z), np.zeros(2), atol=0)


def test_range_bearing_residual_wraps():
    sensor = seif.RangeBearingModel(0.1, 0.05)
    r = sensor.residual(np.array([1.0, np.pi - 0.1]), np.array([1.0, -np.pi + 0.1]))
    np.testing.assert_allclose(r, [0.0, -0.2], atol=1e-12)
    np.testing.assert_array_equal(sensor.noise, seif.diagonal_noise(0.1, 0.05))
    # The period its residual wraps the bearing with; a Cartesian point wraps nothing.
    np.testing.assert_array_equal(sensor.period, [0.0, 2.0 * np.pi])
    np.testing.assert_array_equal(seif.CartesianModel(np.eye(2)).period, [0.0, 0.0])


@pytest.mark.parametrize("model,u", [
    (seif.VelocityModel(0.05, 0.02, "per-step"), seif.VelocityControl(0.3, 0.4, 1.5)),
    (seif.VelocityModel(0.05, 0.02, seif.NoiseForm.Rate), seif.VelocityControl(0.3, 0.0, 0.5)),
    (seif.AckermannModel(seif.AckermannGeometry(2.83, 0.76, np.array([3.78, 0.5])), 0.05, 0.01),
     seif.AckermannControl(2.0, 0.1, 0.025)),
    (seif.OdometryModel(), seif.OdometryIncrement(np.array([0.4, 0.1, 0.2]), np.diag([0.01, 0.02, 0.003]))),
])
def test_motion_increment(model, u):
    inc = model.linearize(POSE, u)
    assert isinstance(inc, seif.MotionIncrement)
    delta = lambda x: model.linearize(x, u).delta
    np.testing.assert_allclose(inc.J_delta_x, numeric_jacobian(delta, POSE), atol=1e-7)
    np.testing.assert_allclose(inc.U, inc.U.T, atol=0)
    assert np.all(np.linalg.eigvalsh(inc.U) >= -1e-15)
    applied = model.apply(POSE, u)
    np.testing.assert_allclose(applied[:2], POSE[:2] + inc.delta[:2], atol=1e-12)
    assert applied[2] == pytest.approx(seif.wrap_angle(POSE[2] + inc.delta[2]))


def test_velocity_delta_control_jacobian():
    u = seif.VelocityControl(0.3, 0.4, 1.5)
    d, J_x, J_u = seif.velocity_delta(POSE, u)
    f = lambda vw: seif.velocity_delta(POSE, seif.VelocityControl(vw[0], vw[1], 1.5))[0]
    np.testing.assert_allclose(J_u, numeric_jacobian(f, np.array([0.3, 0.4])), atol=1e-7)
    np.testing.assert_allclose(d, seif.VelocityModel(0.1, 0.1).linearize(POSE, u).delta, atol=0)


def test_ackermann_body_velocity():
    model = seif.AckermannModel(seif.AckermannGeometry(), 0.05, 0.01)
    vw, J = model.body_velocity(seif.AckermannControl(2.0, 0.1, 0.025))
    f = lambda s: model.body_velocity(seif.AckermannControl(s[0], s[1], 0.025))[0]
    np.testing.assert_allclose(J, numeric_jacobian(f, np.array([2.0, 0.1])), atol=1e-7)
    g = model.geometry
    assert vw[1] == pytest.approx(vw[0] * np.tan(0.1) / g.wheelbase)
