"""mhbench.optimizers(), problems(), plugins(): the same registries `mhbench list` prints."""

import pytest

import mhbench


def listed(run_cli, kind):
    """{name: {parameter name: its line}} from `mhbench list KIND`."""
    out = run_cli("list", kind).stdout
    entries, current = {}, None
    for line in out.splitlines()[1:]:
        if line.startswith("      ") and current is not None:
            entries[current][line.split()[0]] = line
        elif line.startswith("  ") and line.strip():
            current = line.split()[0]
            entries[current] = {}
    return entries


def shown(value):
    """A default as `mhbench list` prints it."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return "%g" % value
    return str(value)


@pytest.mark.parametrize("kind, function", [("optimizers", mhbench.optimizers), ("problems", mhbench.problems),
                                            ("effects", lambda: mhbench.plugins("effects"))])
def test_same_plugins_and_parameters_as_the_command_line(run_cli, kind, function):
    expected = listed(run_cli, kind)
    got = function()
    assert {p["name"]: sorted(q["name"] for q in p["parameters"]) for p in got} == \
        {name: sorted(params) for name, params in expected.items()}
    for plugin in got:
        for q in plugin["parameters"]:
            words = expected[plugin["name"]][q["name"]].split()
            assert words[1] == q["type"]
            if shown(q["default"]):  # an empty text default leaves no word
                assert words[3] == shown(q["default"])
            assert q["range"] in expected[plugin["name"]][q["name"]]
            if q["minimum"] is not None and q["type"] in ("int", "real"):
                assert q["minimum"] <= q["default"] <= q["maximum"]


def test_unknown_kind_is_an_input_error_naming_the_kinds():
    with pytest.raises(mhbench.InputError, match="optimizers") as raised:
        mhbench.plugins("optimisers")
    assert raised.value.field == "kind"
    assert isinstance(raised.value, ValueError)
