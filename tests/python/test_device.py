"""softhap.DeviceMapping against hand-worked values (a mm, y-up device in a z-up world)."""

import numpy as np
import pytest

import softhap

HALF = np.sqrt(0.5)


def test_mm_y_up_device_round_trip_and_force():
    m = softhap.DeviceMapping(scale=0.001, base_position=(0.1, 0.2, 0.3), base_orientation=(HALF, HALF, 0, 0),
                              force_scale=0.5)
    p, q = m.to_world((10.0, 20.0, 30.0))
    np.testing.assert_allclose(p, (0.11, 0.17, 0.32), atol=1e-15)   # y up -> z up, z -> -y
    np.testing.assert_allclose(q, (HALF, HALF, 0.0, 0.0), atol=1e-15)
    back_p, back_q = m.to_device(p, q)
    np.testing.assert_allclose(back_p, (10.0, 20.0, 30.0), atol=1e-12)
    np.testing.assert_allclose(back_q, (1.0, 0.0, 0.0, 0.0), atol=1e-15)
    f, t = m.force_to_device((0.0, 0.0, 2.0), (0.3, 0.0, 0.0))
    np.testing.assert_allclose(f, (0.0, 1.0, 0.0), atol=1e-15)
    np.testing.assert_allclose(t, (0.15, 0.0, 0.0), atol=1e-15)


def test_bad_mapping_names_the_field():
    with pytest.raises(softhap.Error, match="mapping->force_scale"):
        softhap.DeviceMapping(force_scale=-1.0)
    with pytest.raises(ValueError):
        softhap.DeviceMapping().to_world((1.0, 2.0))
    with pytest.raises(softhap.Error):
        softhap.DeviceMapping().to_world((np.nan, 0.0, 0.0))
