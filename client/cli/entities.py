"""galton-client spawn, load-model, entities, update and delete: the world's entities."""

from __future__ import annotations

import re
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich.table import Table

from galton.client.cli.choices import (
    LIST_HELP,
    EntityKind,
    ModelFormat,
    Shape,
    counted,
    numbers,
    rows,
    split_list,
)
from galton.client.cli.common import (
    JsonOpt,
    console,
    emit,
    run_guarded,
    show_stamp,
    with_client,
)
from galton.client.cli.states import NamesArg
from galton.protocol import TWIST_WIDTH
from galton.protocol.vocabulary import SIZE_LAYOUT

if TYPE_CHECKING:
    import numpy as np

# This group's commands; galton.client.cli.app registers them on the CLI.
commands = typer.Typer()


PANEL = "Scene"
DEFAULT_HALF_SIZE = 0.05  # m, every size number of a body
DEFAULT_PLANE_HALF_SIZE = 50.0  # m
# What each model file suffix holds, when --format is not given.
FORMAT_OF_SUFFIX = {".xml": "mjcf", ".mjcf": "mjcf", ".urdf": "urdf"}

Mass = Annotated[float | None, typer.Option(help="kg per body (default: density 1000).")]
Friction = Annotated[float | None, typer.Option(
    help="Sliding friction coefficient (default: the engine's).")]
Restitution = Annotated[float | None, typer.Option(
    help="Bounce, 0 to 1 (default: the engine's).")]
Rgba = Annotated[str | None, typer.Option(help=f"Colour r,g,b,a in 0..1, {LIST_HELP}.")]
Tags = Annotated[str | None, typer.Option(help=f"Tags, {LIST_HELP}.")]


def body_names(names: list[str], count: int) -> list[str]:
    """The names given, or NAME_0 .. NAME_{count-1} from one name and --count."""
    if count == 1:
        return names
    if len(names) != 1:
        raise typer.BadParameter(f"--count {count} takes one name (a prefix), got {len(names)}")
    return [f"{names[0]}_{i}" for i in range(count)]


def size_values(shape: str, size: str | None) -> tuple[float, ...]:
    if size is not None:
        return tuple(numbers(size, "--size"))
    half = DEFAULT_PLANE_HALF_SIZE if shape == "plane" else DEFAULT_HALF_SIZE
    return (half,) * len(SIZE_LAYOUT[shape])


def mesh_fields(shape: str, size: str | None, mesh: Path | None) -> dict[str, Any]:
    """A mesh's size, vertices and faces: the OBJ file's, else a box of --size half
    sizes; none for the other shapes."""
    if shape != "mesh":
        if mesh is not None:
            raise typer.BadParameter(f"--mesh is for a mesh, not a {shape}")
        return {}
    from galton.client.cli.mesh_files import read_obj
    from galton.protocol.mesh import box_mesh, half_extents
    if mesh is not None:
        vertices, faces = run_guarded(lambda: read_obj(mesh))
    else:
        half = size_values("box", size)
        vertices, faces = box_mesh((half[0], half[1], half[2]))
    return {"size": half_extents(vertices), "vertices": vertices, "faces": faces}


def inertia_values(inertia: str | None) -> tuple[float, float, float] | None:
    if inertia is None:
        return None
    values = numbers(inertia, "--inertia")
    if len(values) != 3:
        raise typer.BadParameter(f"--inertia takes 3 numbers ixx,iyy,izz, got {len(values)}")
    return (values[0], values[1], values[2])


def default_position(shape: str) -> str:
    """Where a body goes unless --pos says: a plane is the ground, at z = 0 (as the SDK's
    ``plane()``); a body 1 m above it."""
    return "0,0,0" if shape == "plane" else "0,0,1"


def positions(pos: str, count: int, spacing: float) -> np.ndarray:
    """x,y,z per body, or one x,y,z for the first body and the rest ``spacing`` apart in x."""
    import numpy as np
    given = numbers(pos, "--pos")
    if len(given) == 3:
        xyz = np.tile(np.asarray(given, dtype=float), (count, 1))
        xyz[:, 0] += spacing * np.arange(count)
        return xyz
    return rows(pos, count, 3, "--pos")


def rgba_values(rgba: str | None) -> tuple[float, float, float, float] | None:
    if rgba is None:
        return None
    values = numbers(rgba, "--rgba")
    if len(values) != 4:
        raise typer.BadParameter(f"--rgba takes 4 numbers r,g,b,a, got {len(values)}")
    return (values[0], values[1], values[2], values[3])


def tag_values(tags: str | None) -> tuple[str, ...] | None:
    return None if tags is None else tuple(split_list(tags, "--tags"))


@commands.command(rich_help_panel=PANEL)
def spawn(
    ctx: typer.Context,
    shape: Annotated[Shape, typer.Argument(help="Shape of every body.", show_default=False)],
    names: NamesArg,
    count: Annotated[int, typer.Option(
        help="Bodies to make from one name: NAME_0, NAME_1, ...", min=1)] = 1,
    size: Annotated[str | None, typer.Option(
        help=f"Half sizes, {LIST_HELP} (sphere: radius; box: x,y,z; cylinder and capsule: "
             "radius,half length; plane: x,y). Default 0.05 m each, plane 50 m.")] = None,
    pos: Annotated[str | None, typer.Option(
        help=f"Positions x,y,z per body, {LIST_HELP}; or one x,y,z for the first body, the "
             "others --spacing apart in x. Default: a plane at 0,0,0 (the ground, as the "
             "SDK's plane()), other shapes from 0,0,1.", show_default=False)] = None,
    spacing: Annotated[float, typer.Option(help="x distance between bodies, m.")] = 0.2,
    twists: Annotated[str | None, typer.Option(
        help=f"Initial twists vx,vy,vz,wx,wy,wz per body or one for all, {LIST_HELP}.")
    ] = None,
    static: Annotated[bool, typer.Option(help="Fixed in the world (a plane always is).")
                      ] = False,
    mass: Mass = None,
    friction: Friction = None,
    restitution: Restitution = None,
    rgba: Rgba = None,
    tags: Tags = None,
    mesh: Annotated[Path | None, typer.Option(
        help="For a mesh: a Wavefront OBJ file of its vertices and faces, in the body's "
             "frame (default: a box of --size half sizes).", dir_okay=False, exists=True)
    ] = None,
    inertia: Annotated[str | None, typer.Option(
        help="A moving body's diagonal inertia ixx,iyy,izz, kg m² (default: its shape's).")
    ] = None,
    as_json: JsonOpt = False,
) -> None:
    """Spawn bodies of one shape and material, in a single request."""
    from galton.client.sdk.client import body_group
    every = body_names(names, count)
    fields = mesh_fields(str(shape), size, mesh)
    group = body_group(
        str(shape), fields.pop("size", None) or size_values(shape, size), every,
        positions(pos or default_position(shape), len(every), spacing),
        twists=None if twists is None else rows(twists, len(every), TWIST_WIDTH, "--twists"),
        static=static or shape == "plane", mass=mass, friction=friction,
        restitution=restitution, rgba=rgba_values(rgba), tags=tag_values(tags) or (),
        inertia=inertia_values(inertia), **fields)
    spawned = with_client(ctx, lambda c: c.spawn(group))
    emit({"names": spawned}, as_json, lambda: console.print(
        f"spawned {counted(len(spawned), 'body', 'bodies')}: {', '.join(spawned[:5])}"
        f"{', ...' if len(spawned) > 5 else ''}", markup=False))


def model_format(fmt: ModelFormat | None, file: Path | None, path: str | None) -> str:
    """--format, or the one the file's suffix names."""
    if fmt is not None:
        return str(fmt)
    suffix = Path(path or str(file)).suffix.lower()
    if suffix not in FORMAT_OF_SUFFIX:
        raise typer.BadParameter(f"cannot tell the format from {suffix or 'no suffix'!r}; "
                                 "give --format")
    return FORMAT_OF_SUFFIX[suffix]


def model_text(file: Path) -> str:
    try:
        return file.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as error:
        raise typer.BadParameter(f"--file {str(file)!r} cannot be read as text: {error}") \
            from None


@commands.command("load-model", rich_help_panel=PANEL)
def load_model(
    ctx: typer.Context,
    file: Annotated[Path | None, typer.Option(
        help="A model file on this machine: its text is sent.", exists=True, dir_okay=False)
    ] = None,
    path: Annotated[str | None, typer.Option(
        help="A model file on the daemon's machine: the daemon reads it.")] = None,
    fmt: Annotated[ModelFormat | None, typer.Option(
        "--format", help="Model format (default: from the suffix, .xml is mjcf).")] = None,
    prefix: Annotated[str, typer.Option(
        help="Names the model's entities and joints PREFIX/<name>, as the ROS 2 front names "
             "a spawned model's; a PREFIX that ends in a separator (/ _ - . :) is prepended "
             "as it is (f_ gives f_<name>).")] = "",
    fixed_base: Annotated[bool | None, typer.Option(
        "--fixed-base/--floating-base",
        help="URDF: weld the root link to the world, or give it a free joint (default: "
             "fixed). An MJCF file says itself.", show_default=False)] = None,
    search_path: Annotated[str | None, typer.Option(
        help=f"Folders on the daemon's machine where the files the model names (meshes, "
             f"package://) are looked for, {LIST_HELP}.")] = None,
    as_json: JsonOpt = False,
) -> None:
    """Load an MJCF or URDF model into the world: each model's root and links become
    entities, its joints appear in joints."""
    if (file is None) == (path is None):
        raise typer.BadParameter("give exactly one of --file and --path")
    chosen = model_format(fmt, file, path)
    text = None if file is None else model_text(file)
    folders = None if search_path is None else split_list(search_path, "--search-path")
    if file is not None:
        folders = with_own_folder(file, text or "", folders)
    loaded = with_client(ctx, lambda c: c.load_model(
        chosen, text=text, path=path, prefix=separated(prefix), fixed_base=fixed_base,
        search_path=folders))
    emit({"names": loaded}, as_json, lambda: console.print(
        f"loaded {counted(len(loaded), 'entity', 'entities')}: {', '.join(loaded)}", markup=False))


PREFIX_SEPARATORS = ("/", "_", "-", ".", ":")


def separated(prefix: str) -> str:
    """load-model's --prefix as the wire's ``prefix``: ``arm`` names links ``arm/<link>``
    (the ROS 2 front's rule), not ``arm<link>``; one ending in a separator stays as it is."""
    if not prefix or prefix.endswith(PREFIX_SEPARATORS):
        return prefix
    return f"{prefix}/"


# An attribute by which a URDF or MJCF file names another file (a mesh, a texture, ...).
_NAMES_A_FILE = re.compile(r"\b(?:file|filename)\s*=")


def with_own_folder(file: Path, text: str, folders: list[str] | None) -> list[str] | None:
    """The search path with the model file's own folder first, when the model names other
    files (its meshes sit beside it): the daemon gets the text, not the path. A model that
    names none is sent as it was, so a daemon on another machine is not asked to search a
    folder it lacks."""
    if not _NAMES_A_FILE.search(text):
        return folders
    own = str(file.resolve().parent)
    return [own, *(f for f in folders or [] if f != own)]


@commands.command(rich_help_panel=PANEL)
def entities(
    ctx: typer.Context,
    name: Annotated[str | None, typer.Option(help="Name glob, * and ? (quote it).")] = None,
    tag: Annotated[str | None, typer.Option(help="Only entities with this tag.")] = None,
    kind: Annotated[EntityKind | None, typer.Option(help="Only static or dynamic ones.")
                    ] = None,
    as_json: JsonOpt = False,
) -> None:
    """List the scene's entities (the protocol's list), with shape, size and material."""
    found = with_client(ctx, lambda c: c.list(name, tag, None if kind is None else str(kind)))

    def render() -> None:
        table = Table("name", "shape", "half sizes (m)", "static", "mass (kg)", "friction",
                      "restitution", "tags", "source")
        for e in found:
            table.add_row(e.name, e.shape, ", ".join(f"{s:g}" for s in e.size), str(e.static),
                          _maybe(e.mass), _maybe(e.friction), _maybe(e.restitution),
                          ", ".join(e.tags), e.source)
        console.print(table if found else "no entity")
    emit([e.to_wire() for e in found], as_json, render)


def _maybe(value: float | None) -> str:
    return "–" if value is None else f"{value:.4g}"


@commands.command(rich_help_panel=PANEL)
def update(
    ctx: typer.Context,
    names: NamesArg,
    mass: Mass = None,
    friction: Friction = None,
    restitution: Restitution = None,
    rgba: Rgba = None,
    tags: Annotated[str | None, typer.Option(help=f"Tags replacing the old, {LIST_HELP}.")
                    ] = None,
    as_json: JsonOpt = False,
) -> None:
    """Change mass, friction, restitution, colour or tags of entities (one request)."""
    properties: dict[str, Any] = {"mass": mass, "friction": friction,
                                  "restitution": restitution, "rgba": rgba_values(rgba),
                                  "tags": tag_values(tags)}
    given = {key: value for key, value in properties.items() if value is not None}
    if not given:
        raise typer.BadParameter("give at least one property to change")
    stamp = with_client(ctx, lambda c: c.update(names, **given))
    show_stamp(f"updated {counted(len(names), 'entity', 'entities')}", stamp, as_json, names=names)


@commands.command(rich_help_panel=PANEL)
def delete(ctx: typer.Context, names: NamesArg, as_json: JsonOpt = False) -> None:
    """Remove entities in one request (all or none: an unknown name deletes nothing)."""
    stamp = with_client(ctx, lambda c: c.delete(names))
    show_stamp(f"deleted {counted(len(names), 'entity', 'entities')}", stamp, as_json, names=names)

