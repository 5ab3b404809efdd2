"""Engine checks of bad input: parameters and models the interface says an engine refuses,
with the typed error it names, leaving the engine as it was and still working."""

from __future__ import annotations

import functools
from collections.abc import Callable

from galton.daemon.core.params import KNOWN_ENGINES
from galton.daemon.engines.base import FEATURE_LOAD_MODEL, Engine
from galton.daemon.engines.check.support import (
    CheckContext,
    CheckSkippedError,
    Snapshot,
    expect,
    expect_raises,
    group,
    skip_unless,
    states,
)
from galton.protocol import (
    FeatureUnsupportedError,
    InvalidArgumentError,
    NameNotUniqueError,
)

# One free body per format, for the engines that load that format.
PROBE_MODELS = {
    "mjcf": """<mujoco model="probe"><worldbody>
  <body name="crate" pos="0 0 1"><freejoint/>
    <geom type="box" size=".1 .1 .1" mass="2"/></body>
</worldbody></mujoco>""",
    "urdf": """<robot name="probe"><link name="crate">
  <inertial><mass value="2"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
  <collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision>
</link></robot>""",
}
MISSING_PATH = "/nonexistent/galton-engine-check/model.xml"


def _busy(engine: Engine) -> list[str]:
    """A few moving bodies a refused call must not disturb; their names."""
    names = ["a", "b"]
    engine.spawn([group("sphere", names, [[0, 0, 1], [1, 0, 2]], twists=[[1, 0, 0, 0, 0, 2]]
                        * 2, friction=0.6)])
    engine.step(2)
    return names


def _refused(engine: Engine, names: list[str], errors: type[Exception] | tuple[
        type[Exception], ...], what: str, call: Callable[[], object]) -> None:
    """``call`` raises one of ``errors`` and leaves these bodies and the parameters as
    they were."""
    before = Snapshot.of(engine, names)
    with expect_raises(errors, what):
        call()
    before.expect_same(engine, f"after {what}")


def check_bad_params(ctx: CheckContext) -> None:
    """set_params is all or none: an unknown name is InvalidArgumentError with a "did you
    mean", another engine's parameter FeatureUnsupportedError, a bad value
    InvalidArgumentError; none of them changes a parameter, even one given beside it."""
    engine = ctx.engine
    names = _busy(engine)
    params, half = engine.get_params(), engine.timestep / 2
    good = {"timestep": half} if "timestep" in params else {}
    _refused(engine, names, InvalidArgumentError, "set_params with a misspelt name",
             lambda: engine.set_params({**good, "timestpe": half}))
    if "timestep" in params:
        try:
            engine.set_params({"timestpe": half})
        except InvalidArgumentError as exc:
            expect("did you mean 'timestep'" in str(exc), "the refusal of 'timestpe'",
                   "a message with \"did you mean 'timestep'\"", str(exc))
    foreign = next(e for e in (*KNOWN_ENGINES, "mujoco", "other") if e != engine.name)
    _refused(engine, names, FeatureUnsupportedError, f"set_params with a {foreign} parameter",
             lambda: engine.set_params({**good, f"{foreign}.solver": 1}))
    bad_values: dict[str, object] = {"timestep": -1.0, "gravity": "down"}
    for name, value in bad_values.items():
        if name in params:
            _refused(engine, names, InvalidArgumentError, f"set_params {name}={value!r}",
                     functools.partial(engine.set_params, {name: value}))


def _model_format(engine: Engine) -> str:
    skip_unless(engine, FEATURE_LOAD_MODEL)
    formats = [f for f in engine.capabilities().model_formats if f in PROBE_MODELS]
    if not formats:
        raise CheckSkippedError(f"the checker has no probe model in the engine's formats "
                           f"{engine.capabilities().model_formats}")
    return formats[0]


def check_load_model(ctx: CheckContext) -> None:
    """A model loads as entities named prefix + body name, source "model", whose states
    read back; another prefix loads it again beside the first."""
    engine = ctx.engine
    fmt = _model_format(engine)
    for prefix in ("m/", "n/"):
        infos = engine.load_model(fmt, PROBE_MODELS[fmt], None, prefix)
        expect(bool(infos), f"load_model({fmt!r})", "at least one entity", infos)
        wrong = [i.name for i in infos if not i.name.startswith(prefix) or i.source != "model"]
        expect(not wrong, "loaded entities", f"names starting {prefix!r}, source 'model'",
               wrong)
        states(engine, [i.name for i in infos])


def check_bad_models(ctx: CheckContext) -> None:
    """load_model refuses an unknown format (FeatureUnsupportedError), a model that does not
    parse or a file that is not there (InvalidArgumentError), and a body name in use
    (NameNotUniqueError or InvalidArgumentError), each leaving the world as it was."""
    engine = ctx.engine
    fmt = _model_format(engine)
    text = PROBE_MODELS[fmt]
    names = _busy(engine) + [i.name for i in engine.load_model(fmt, text, None, "m/")]
    _refused(engine, names, FeatureUnsupportedError, "load_model of format 'no-such-format'",
             lambda: engine.load_model("no-such-format", text, None, "x/"))
    _refused(engine, names, InvalidArgumentError, f"load_model of half a {fmt} model",
             lambda: engine.load_model(fmt, text[:len(text) // 2], None, "x/"))
    _refused(engine, names, InvalidArgumentError, "load_model of a missing file",
             lambda: engine.load_model(fmt, None, MISSING_PATH, "x/"))
    _refused(engine, names, (NameNotUniqueError, InvalidArgumentError),
             "load_model with a body name in use", lambda: engine.load_model(
                 fmt, text, None, "m/"))
    expect(bool(engine.load_model(fmt, text, None, "y/")), "load_model after refusals",
           "a model loaded", "nothing")
