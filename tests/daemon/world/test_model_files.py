"""The files a model names are resolved by the daemon before an engine sees the model:
package:// and relative references become absolute, a missing file is refused by name."""

from __future__ import annotations

import os
from pathlib import Path

import pybullet_data
import pytest

from galton.daemon.world.model_files import resolve_model, search_folders
from galton.protocol import InvalidArgumentError

DATA = Path(pybullet_data.getDataPath())
PANDA = DATA / "franka_panda" / "panda.urdf"
MJCF = """<mujoco><compiler meshdir="meshes"/><asset><mesh name="m" file="part.obj"/></asset>
<worldbody><body><geom type="mesh" mesh="m"/></body></worldbody></mujoco>"""


def test_package_references_resolve_against_the_models_folder() -> None:
    text = resolve_model("urdf", PANDA.read_text(), str(PANDA), [])
    assert "package://" not in text
    assert text.count(str(DATA / "franka_panda" / "meshes")) == 22


def test_a_model_given_as_text_finds_its_files_in_the_search_path() -> None:
    folders = search_folders(str(DATA / "franka_panda"))
    text = resolve_model("urdf", PANDA.read_text(), None, folders)
    assert "package://" not in text


def test_a_missing_file_is_refused_by_name() -> None:
    with pytest.raises(InvalidArgumentError, match=r"link0\.obj.*search_path") as caught:
        resolve_model("urdf", PANDA.read_text(), None, [])
    assert caught.value.details["missing_file"] == "package://meshes/collision/link0.obj"


def test_mjcf_meshdir_is_followed_and_then_dropped(tmp_path: Path) -> None:
    (tmp_path / "meshes").mkdir()
    (tmp_path / "meshes" / "part.obj").write_text("v 0 0 0\n")
    model = tmp_path / "model.xml"
    model.write_text(MJCF)
    text = resolve_model("mjcf", MJCF, str(model), [])
    assert f'file="{tmp_path / "meshes" / "part.obj"}"' in text
    assert 'meshdir="' not in text


def test_a_model_without_files_is_passed_through_unchanged() -> None:
    text = (DATA / "cartpole.urdf").read_text()
    assert resolve_model("urdf", text, None, []) is text


def test_search_paths_must_be_absolute_folders(tmp_path: Path) -> None:
    assert search_folders(f"{tmp_path}{os.pathsep}{DATA}") == [tmp_path, DATA]
    for bad in ("relative/folder", str(PANDA), str(tmp_path / "absent")):
        with pytest.raises(InvalidArgumentError, match="not an absolute path to a folder"):
            search_folders(bad)


def test_xml_that_does_not_parse_is_refused() -> None:
    with pytest.raises(InvalidArgumentError, match="not well-formed"):
        resolve_model("urdf", "<robot", None, [])
