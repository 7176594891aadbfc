"""The report renderer: placeholders filled with fixed digits, a missing record named, the output
deterministic, and the records of several workers merged (``tests/validation_report.py``)."""

import json

import pytest

import validation_report as vr

TEMPLATE = """# Report
{{stats}}

| check | measured | tolerance | test | reference |
|---|---|---|---|---|
| λc(0.6) | {{geometry.lam_c_0.6:.5f}} | {{geometry.lam_c_0.6@tol}} | {{geometry.lam_c_0.6@test}} | {{geometry.lam_c_0.6@kind}} |
| pinned | {{drop.V_ca_0.3:.9f}} | {{drop.V_ca_0.3@tol}} | {{drop.V_ca_0.3@test}} | {{drop.V_ca_0.3@kind}} |
| stored | {{json:cases.json#cases/1/V:.4f}} | {{json:cases.json#cases/len()}} cases | | |

## Later <!-- not yet generated -->
λ_T(0.8) = 1.142 and 21.7 %.
"""


def records():
    store = {}
    vr.Recorder("tests/lubrication/test_geometry.py::test_chen", False, store).value(
        "geometry.lam_c_0.6", 1.9812012345, reference=1.98, tol="±0.005",
        source="Chen et al. 2020")
    vr.Recorder("tests/bem/test_drop.py::test_regression_values", False, store).value(
        "drop.V_ca_0.3", 1.600922961234, reference=1.600922961, tol=1e-7, kind="regression")
    return store


@pytest.fixture
def data_dir(tmp_path):
    (tmp_path / "cases.json").write_text(json.dumps({"cases": [{"V": 1.0}, {"V": 1.25678}]}))
    return tmp_path


def test_placeholders_are_filled_with_fixed_digits(data_dir):
    text, counts = vr.render(TEMPLATE, records(), data_dir)
    assert "{{" not in text
    assert "| λc(0.6) | 1.98120 | ±0.005 | `test_geometry.py::test_chen` | independent |" in text
    assert ("| pinned | 1.600922961 | 1e-07 | `test_drop.py::test_regression_values` "
            "| regression |") in text
    assert "| stored | 1.2568 | 2 cases |" in text
    assert counts["values"] == 4 and counts["independent"] == 1 and counts["regression"] == 1
    assert counts["stored"] == 2 and counts["untraced"] == 3 and counts["unused"] == []
    assert "4 numbers generated" in text


def test_output_is_deterministic(data_dir):
    first = vr.render(TEMPLATE, records(), data_dir)[0]
    assert vr.render(TEMPLATE, records(), data_dir)[0] == first


@pytest.mark.parametrize("drop, message", [
    ("drop.V_ca_0.3", "{{drop.V_ca_0.3}} has no record"),
])
def test_a_missing_record_is_an_error_naming_the_placeholder(data_dir, drop, message):
    store = records()
    del store[drop]
    with pytest.raises(vr.MissingRecord, match=message.replace(".", r"\.").replace("{", r"\{")
                       .replace("}", r"\}")):
        vr.render(TEMPLATE, store, data_dir)


def test_a_missing_stored_value_is_an_error_naming_the_placeholder(data_dir):
    with pytest.raises(vr.MissingRecord, match=r"json:cases\.json#cases/7/V"):
        vr.render("{{json:cases.json#cases/7/V:.3f}}", {}, data_dir)


def test_a_float_without_a_format_is_refused(data_dir):
    with pytest.raises(ValueError, match="geometry.lam_c_0.6"):
        vr.render("{{geometry.lam_c_0.6}}", records(), data_dir)


def test_workers_are_merged_and_slow_records_kept(tmp_path):
    store = records()
    slow = {}
    vr.Recorder("tests/bem/test_vesicle.py::test_long", True, slow).value(
        "bem.gamma_max", 1009.85, reference=1.2e3, tol="3 %")
    slow_file = tmp_path / "slow.json"
    # a run with the slow test stores its record in the committed file ...
    vr.save_records(tmp_path / "run1", {**store, **slow})
    merged = vr.load_records(tmp_path / "run1", slow_file, update_slow=True)
    assert set(json.loads(slow_file.read_text())) == {"bem.gamma_max"}
    assert set(merged) == {"geometry.lam_c_0.6", "drop.V_ca_0.3", "bem.gamma_max"}
    # ... which a default run, without it, reuses
    vr.save_records(tmp_path / "run2", store)
    assert vr.load_records(tmp_path / "run2", slow_file) == merged


def test_one_key_from_two_tests_is_refused():
    store = records()
    with pytest.raises(ValueError, match="geometry.lam_c_0.6"):
        vr.Recorder("tests/x.py::other", False, store).value("geometry.lam_c_0.6", 2.0)



def test_max_and_min_aggregate_a_parametrized_test(data_dir):
    store = {}
    for k, err in ((0.3, 1e-12), (0.9, 4e-10)):
        vr.Recorder(f"tests/lubrication/test_equations.py::test_cylinder[{k}]", False, store).value(
            f"lub.cylinder_{k}", err, reference=0.0, tol="1e-9 rel")
    text, counts = vr.render("{{max:lub.cylinder_*:.1e}} {{min:lub.cylinder_*:.0e}} "
                             "{{max:lub.cylinder_*@tol}} {{max:lub.cylinder_*@test}}", store,
                             data_dir)
    assert text == "4.0e-10 1e-12 1e-9 rel `test_equations.py::test_cylinder`"
    assert counts["unused"] == []
    with pytest.raises(vr.MissingRecord, match=r"max:lub\.sphere_\*"):
        vr.render("{{max:lub.sphere_*:.1e}}", store, data_dir)


def test_a_fresh_record_may_not_shadow_a_committed_one_of_another_test(tmp_path):
    slow = {}
    vr.Recorder("tests/bem/test_sphere.py::test_study[6]", True, slow).value("sphere.order6", 6.1)
    slow_file = tmp_path / "slow.json"
    slow_file.write_text(json.dumps(slow))
    fast = {}
    vr.Recorder("tests/bem/test_sphere.py::test_fast", False, fast).value("sphere.order6", 5.9)
    vr.save_records(tmp_path / "run", fast)
    with pytest.raises(ValueError, match="sphere.order6"):
        vr.load_records(tmp_path / "run", slow_file)


def test_a_benchmark_not_measured_renders_its_fallback_text(data_dir):
    """``bench_*.json`` placeholders may carry ``|text``: a missing file or entry gives the text
    and is counted as not measured; a present value is formatted and counted as stored."""
    stored = {"cases": {"short": {"median_s": 3.456}}}
    (data_dir / "bench_speed.json").write_text(json.dumps(stored))
    template = ("{{json:bench_speed.json#cases/short/median_s:.1f|not measured}} / "
                "{{json:bench_speed.json#cases/long/median_s:.1f|not measured}} / "
                "{{json:bench_other.json#median_s:.2f|not measured}}\n{{stats}}")
    text, counts = vr.render(template, {}, data_dir)
    assert text.splitlines()[0] == "3.5 / not measured / not measured"
    assert counts["stored"] == 1 and counts["not_measured"] == 2
    assert "(2 benchmark values not measured)" in text


def test_a_fallback_text_is_refused_outside_the_benchmark_files(data_dir):
    with pytest.raises(ValueError, match="only for the benchmark files"):
        vr.render("{{json:cases.json#cases/7/V:.3f|not measured}}", {}, data_dir)


def test_join_lists_numbers_and_fields_of_a_stored_list(data_dir):
    (data_dir / "grid.json").write_text(json.dumps({"ca": [5.0, 9.0, 150.0], "none": [],
                                                    "holes": [{"nu": 0.6, "r": 0.85},
                                                              {"nu": 0.65, "r": 0.5}]}))
    text = vr.render("{{json:grid.json#ca/join()}}; {{json:grid.json#holes/join(nu,r)}}; "
                     "{{json:grid.json#none/join()}}", {}, data_dir)[0]
    assert text == "5, 9, 150; (0.6, 0.85), (0.65, 0.5); none"
    with pytest.raises(vr.MissingRecord, match=r"without the numbers \['ca_b'\]"):
        vr.render("{{json:grid.json#holes/join(ca_b)}}", {}, data_dir)
