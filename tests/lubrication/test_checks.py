"""Input checks and validity ranges: messages name parameter, value and range."""

import math
import warnings

import numpy as np
import pytest
from hypothesis import given, strategies as st

from lubrication.checks import (InvalidParameterError, OutOfRangeWarning, ValidityRange, as_finite,
                                check_choice, check_fraction, check_positive, check_range,
                                scalar_or_array)

RANGE = ValidityRange.of("Test et al. 2020", nu=(0.6, 0.93), lam=(0.6, 1.8))


@given(x=st.floats(allow_nan=True, allow_infinity=True))
def test_check_positive_accepts_exactly_the_positive_finite_numbers(x):
    if math.isfinite(x) and x > 0:
        assert check_positive("size", x) == x
    else:
        with pytest.raises(InvalidParameterError, match=r"^size=.* is invalid: valid range size > 0"):
            check_positive("size", x)


@given(x=st.floats(-2.0, 2.0))
def test_check_range_closed_and_open_ends(x):
    inside = 0.0 < x <= 1.0
    if inside:
        check_range("nu", x, 0.0, 1.0, lo_open=True)
    else:
        with pytest.raises(InvalidParameterError, match=r"0 < nu <= 1"):
            check_range("nu", x, 0.0, 1.0, lo_open=True)


def test_array_message_names_first_offending_element():
    with pytest.raises(InvalidParameterError, match=r"x=-2 \(first offending element of an array of shape \(1,\)\)"):
        check_positive("x", [1.0, -2.0, 3.0])


def test_fraction_hint_for_percentages():
    with pytest.raises(InvalidParameterError, match="fraction, not a percentage"):
        check_fraction("tube_hematocrit", 45)
    assert check_fraction("tube_hematocrit", 0.0) == 0.0


def test_choice_names_the_choices():
    with pytest.raises(InvalidParameterError, match=r"law='bogus' .*'pries1992', 'pries1994'"):
        check_choice("law", "bogus", ("pries1992", "pries1994"))


def test_non_numbers_are_rejected_by_name():
    with pytest.raises(InvalidParameterError, match="volume="):
        as_finite("volume", "ninety")


@given(shape=st.sampled_from([(), (3,), (2, 2)]))
def test_scalar_or_array_convention(shape):
    out = scalar_or_array(np.zeros(shape))
    assert isinstance(out, float) if shape == () else out.shape == shape


@given(nu=st.floats(0.0, 1.0), lam=st.floats(0.0, 3.0))
def test_validity_range_membership_distance_and_warning(nu, lam):
    inside = 0.6 <= nu <= 0.93 and 0.6 <= lam <= 1.8
    assert RANGE.contains(nu=nu, lam=lam) is inside
    assert (RANGE.distance(nu=nu, lam=lam) == 0.0) is inside
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert RANGE.warn_outside("f", nu=nu, lam=lam) is inside
    assert len(caught) == (0 if inside else 1)
    if not inside:
        assert issubclass(caught[0].category, OutOfRangeWarning)
        assert "Test et al. 2020" in str(caught[0].message)


def test_validity_range_ignores_parameters_it_does_not_bound():
    assert RANGE.contains(nu=0.7, other=1e9)
    assert RANGE.contains(lam=1.0)            # nu not given: not checked
    assert RANGE.describe() == "0.6 <= nu <= 0.93, 0.6 <= lam <= 1.8 (Test et al. 2020)"
