import pytest

from skelcore.params import Params, k_center_for


def test_defaults_reproduce_reference_tool():
    p = Params()
    assert p.beta_star == 0.75 and p.c_star == 0.75
    assert p.normalize_by == "longest_side" and p.normalized_size == 1.6
    assert p.boundedness_method == "rays"


@pytest.mark.parametrize(
    "change",
    [
        {"beta_star": 1.5},
        {"boundedness_method": "magic"},
        {"normalize_by": "volume"},
        {"eps_quantile": 0.0},
        {"curve_samples": 0},
        {"ring_growth": 1.0},
        {"k_center": 0},
    ],
)
def test_invalid_values_are_rejected_with_the_field_name(change):
    with pytest.raises(ValueError, match=next(iter(change))):
        Params(**change)


def test_unknown_field_fails_loudly():
    with pytest.raises(ValueError, match="unknown parameter"):
        Params().replace(no_such_thing=1)


def test_set_strings_convert_to_field_types():
    p = Params().with_strings(["beta_star=0.5", "curve_samples=50", "boundedness_method=paper", "k_center=12"])
    assert p.beta_star == 0.5 and p.curve_samples == 50 and p.boundedness_method == "paper" and p.k_center == 12
    assert Params(k_center=5).with_strings(["k_center=auto"]).k_center is None
    with pytest.raises(ValueError):
        Params().with_strings(["beta_star"])
    with pytest.raises(ValueError, match="curve_samples"):
        Params().with_strings(["curve_samples=many"])


@pytest.mark.parametrize(
    "n, k",
    [(100, 10), (999, 10), (1049, 10), (1050, 11), (2000, 20), (5000, 50), (5049, 50), (5050, 30), (100000, 30)],
)
def test_k_center_keeps_reference_quirk(n, k):
    # round(0.01 N), <10 -> 10, >50 -> 30; MATLAB rounds half away from zero (10.5 -> 11)
    assert k_center_for(n, Params()) == k


def test_k_center_explicit_overrides_rule():
    assert k_center_for(100000, Params(k_center=7)) == 7
