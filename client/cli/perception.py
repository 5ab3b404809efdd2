"""galton-client render, add-camera, remove-camera, cameras, raycast and contacts: what the
world looks like and touches (docs/protocol.md, "render" to "contacts").

A camera is --camera NAME (one kept with add-camera) or --eye and --target (x,y,z) with
--up, --fov, --size WIDTHxHEIGHT, --near, --far and --attach. render writes PNGs: --out the
RGB picture, --depth-out the depth (16-bit millimetres; a .npy file keeps float32 metres),
--seg-out the segmentation (16-bit entity index + 1; .npy keeps int32 indices).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich.table import Table

from galton.client.cli.choices import LIST_HELP, numbers, split_list
from galton.client.cli.common import JsonOpt, console, emit, with_client

if TYPE_CHECKING:
    pass

if TYPE_CHECKING:
    import numpy as np

    from galton.client.sdk.values import Contacts, Image, RayHits

# This group's commands; galton.client.cli.app registers them on the CLI.
commands = typer.Typer()

PANEL = "Perception"
XYZ = "x,y,z"
EyeOpt = Annotated[str | None, typer.Option(help=f"Where the camera is ({XYZ}, m).",
                                            metavar=XYZ)]
TargetOpt = Annotated[str | None, typer.Option(help=f"What it looks at ({XYZ}, m).",
                                               metavar=XYZ)]
UpOpt = Annotated[str | None, typer.Option(
    help=f"Its up direction ({XYZ}); default 0,0,1.", metavar=XYZ)]
FovOpt = Annotated[float | None, typer.Option(
    help="Vertical field of view, degrees; default 45.")]
SizeOpt = Annotated[str | None, typer.Option(
    help="WIDTHxHEIGHT in pixels; default 320x240.", metavar="WxH")]
NearOpt = Annotated[float | None, typer.Option(help="Near clip, m; default 0.01.")]
FarOpt = Annotated[float | None, typer.Option(help="Far clip, m; default 100.")]
AttachOpt = Annotated[str | None, typer.Option(
    help="A body or link: eye, target and up are then in its frame and move with it.")]
CameraNameArg = Annotated[str, typer.Argument(help="The camera's name.", show_default=False)]


def point(text: str | None, where: str) -> list[float] | None:
    if text is None:
        return None
    values = numbers(text, where)
    if len(values) != 3:
        raise typer.BadParameter(f"{where} takes x,y,z (3 numbers), got {text!r}")
    return values


def size_of(text: str | None) -> tuple[int, int] | None:
    if text is None:
        return None
    width, sep, height = text.lower().partition("x")
    if not sep or not width.isdigit() or not height.isdigit():
        raise typer.BadParameter(f"--size takes WIDTHxHEIGHT, e.g. 640x480, got {text!r}")
    return int(width), int(height)


def camera_map(eye: str | None, target: str | None, up: str | None, fov: float | None,
               size: str | None, near: float | None, far: float | None, attach: str | None,
               outputs: list[str] | None) -> dict[str, Any]:
    """A camera map from the command's options (--eye and --target required)."""
    from galton.client.sdk.perception import camera
    seen, looked_at = point(eye, "--eye"), point(target, "--target")
    if seen is None or looked_at is None:
        raise typer.BadParameter("a camera needs --eye and --target (or --camera NAME)")
    return camera(seen, looked_at, up=point(up, "--up"), fov=fov, size=size_of(size),
                  near=near, far=far, outputs=outputs, attach=attach)


def write_image(image: Image, out: Path | None, depth_out: Path | None,
                seg_out: Path | None) -> list[str]:
    """Write the asked files; return their paths."""
    import numpy as np

    from galton.protocol.png import depth_png, encode_png, segmentation_png
    written: list[str] = []
    for path, pixels, png in ((out, image.rgb, encode_png), (depth_out, image.depth, depth_png),
                              (seg_out, image.segmentation, segmentation_png)):
        if path is None or pixels is None:
            continue
        if path.suffix == ".npy":
            np.save(path, pixels)
        else:
            path.write_bytes(png(pixels))
        written.append(str(path))
    return written


@commands.command(rich_help_panel=PANEL)
def render(
    ctx: typer.Context,
    out: Annotated[Path | None, typer.Option(help="Write the RGB picture here (PNG).")] = None,
    depth_out: Annotated[Path | None, typer.Option(
        help="Write the depth here: PNG of millimetres, or .npy of metres.")] = None,
    seg_out: Annotated[Path | None, typer.Option(
        help="Write the segmentation here: PNG of index + 1, or .npy of indices.")] = None,
    name: Annotated[str | None, typer.Option(
        "--camera", help="A named camera (add-camera) instead of --eye/--target.")] = None,
    eye: EyeOpt = None, target: TargetOpt = None, up: UpOpt = None, fov: FovOpt = None,
    size: SizeOpt = None, near: NearOpt = None, far: FarOpt = None, attach: AttachOpt = None,
    as_json: JsonOpt = False,
) -> None:
    """Render one camera and write its pictures (give at least one of --out, --depth-out,
    --seg-out); prints the size and the files, and with --seg-out the entities seen."""
    import numpy as np
    wanted = [kind for kind, path in (("rgb", out), ("depth", depth_out),
                                      ("segmentation", seg_out)) if path is not None]
    if not wanted:
        raise typer.BadParameter("give at least one of --out, --depth-out, --seg-out")
    chosen: dict[str, Any] = ({"camera": name, "outputs": wanted} if name is not None else
                              camera_map(eye, target, up, fov, size, near, far, attach, wanted))
    (image,) = with_client(ctx, lambda c: c.render(chosen))
    files = write_image(image, out, depth_out, seg_out)
    seen = [] if image.segmentation is None else sorted(
        image.labels[i] for i in set(np.unique(image.segmentation).tolist()) if i >= 0)
    found = {"width": image.width, "height": image.height, "files": files, "step": image.step,
             "sim_time": image.sim_time, **({"seen": seen} if seen else {})}
    emit(found, as_json, lambda: console.print(
        f"{image.width}x{image.height} at step {image.step}: {', '.join(files)}"
        + (f" (seen: {', '.join(seen)})" if seen else ""), markup=False))


@commands.command("add-camera", rich_help_panel=PANEL)
def add_camera(
    ctx: typer.Context, name: CameraNameArg,
    eye: EyeOpt = None, target: TargetOpt = None, up: UpOpt = None, fov: FovOpt = None,
    size: SizeOpt = None, near: NearOpt = None, far: FarOpt = None, attach: AttachOpt = None,
    outputs: Annotated[str | None, typer.Option(
        help=f"Among rgb, depth, segmentation ({LIST_HELP}); default rgb.")] = None,
    as_json: JsonOpt = False,
) -> None:
    """Keep a named camera in the world (replacing one of that name): render --camera NAME
    then renders it, following its --attach body as it moves."""
    kinds = None if outputs is None else split_list(outputs, "--outputs")
    made = camera_map(eye, target, up, fov, size, near, far, attach, kinds)
    kept = with_client(ctx, lambda c: c.add_camera(name, made))
    show_cameras({name: kept}, as_json)


@commands.command("remove-camera", rich_help_panel=PANEL)
def remove_camera(ctx: typer.Context, name: CameraNameArg, as_json: JsonOpt = False) -> None:
    """Remove a named camera."""
    with_client(ctx, lambda c: c.remove_camera(name))
    emit({"removed": name}, as_json, lambda: console.print(f"removed camera {name}",
                                                           markup=False))


@commands.command(rich_help_panel=PANEL)
def cameras(ctx: typer.Context, as_json: JsonOpt = False) -> None:
    """List the world's named cameras."""
    show_cameras(with_client(ctx, lambda c: c.cameras()), as_json)


def show_cameras(found: dict[str, dict[str, Any]], as_json: bool) -> None:
    def table() -> None:
        if not found:
            console.print("no camera")
            return
        shown = Table("camera", "eye", "target", "fov", "size", "outputs", "attached to")
        for name, c in found.items():
            shown.add_row(name, _xyz(c["eye"]), _xyz(c["target"]), f"{c['fov']:g}",
                          f"{c['width']}x{c['height']}", ",".join(c["outputs"]),
                          c.get("attach") or "")
        console.print(shown)
    emit([{"name": name, **c} for name, c in found.items()], as_json, table)


def _xyz(values: Any) -> str:
    return ",".join(f"{float(v):.4g}" for v in values)


def ray_rows(text: str, where: str) -> np.ndarray:
    import numpy as np
    values = numbers(text, where)
    if len(values) % 3:
        raise typer.BadParameter(f"{where} takes rows of x,y,z ({len(values)} numbers given)")
    return np.asarray(values, dtype=float).reshape(-1, 3)


@commands.command(rich_help_panel=PANEL)
def raycast(
    ctx: typer.Context,
    origins: Annotated[str, typer.Option(
        "--from", help=f"Ray origins, x,y,z per ray ({LIST_HELP}).", metavar="X,Y,Z...")],
    directions: Annotated[str | None, typer.Option(
        "--dir", help="Directions, x,y,z per ray or one for all.", metavar="X,Y,Z...")] = None,
    ends: Annotated[str | None, typer.Option(
        "--to", help="End points, x,y,z per ray or one for all.", metavar="X,Y,Z...")] = None,
    max_length: Annotated[float | None, typer.Option(
        help="How far rays given --dir reach, m; default 100.")] = None,
    as_json: JsonOpt = False,
) -> None:
    """Cast rays (--from with --dir or --to) and print each one's first hit."""
    import numpy as np
    if (directions is None) == (ends is None):
        raise typer.BadParameter("give exactly one of --dir or --to")
    start = ray_rows(origins, "--from")
    other = ray_rows(directions or ends or "", "--dir" if ends is None else "--to")
    if len(other) == 1:
        other = np.tile(other, (len(start), 1))
    hits = with_client(ctx, lambda c: c.raycast(
        start, directions=other if ends is None else None,
        ends=other if ends is not None else None, max_length=max_length))
    show_hits(hits, as_json)


def show_hits(hits: RayHits, as_json: bool) -> None:
    found: list[dict[str, Any]] = [
        {"hit": bool(hits.hits[i]), "entity": hits.entities[i] or None,
         "point": _finite(hits.points[i]), "normal": _finite(hits.normals[i]),
         "distance": float(hits.distances[i]) if hits.hits[i] else None}
        for i in range(len(hits))]

    def table() -> None:
        shown = Table("ray", "entity", "point", "normal", "distance (m)")
        for i, row in enumerate(found):
            shown.add_row(str(i), row["entity"] or "(miss)", _xyz(row["point"] or []),
                          _xyz(row["normal"] or []),
                          "" if row["distance"] is None else f"{row['distance']:.6g}")
        console.print(shown)
    emit(found, as_json, table)


def _finite(row: np.ndarray) -> list[float] | None:
    import numpy as np
    return [float(v) for v in row] if np.isfinite(row).all() else None


@commands.command(rich_help_panel=PANEL)
def contacts(
    ctx: typer.Context,
    names: Annotated[list[str] | None, typer.Argument(
        help="Entity names, as separate arguments; none: every contact.",
        show_default=False)] = None,
    as_json: JsonOpt = False,
) -> None:
    """The contact points of the last step (only those involving NAMES if given)."""
    show_contacts(with_client(ctx, lambda c: c.contacts(names)), as_json)


def show_contacts(found: Contacts, as_json: bool) -> None:
    rows: list[dict[str, Any]] = [
        {"a": found.a[i], "b": found.b[i], "position": found.positions[i].tolist(),
         "normal": found.normals[i].tolist(), "force": float(found.forces[i]),
         "penetration": float(found.penetrations[i])} for i in range(len(found))]

    def table() -> None:
        if not rows:
            console.print("no contact")
            return
        shown = Table("a", "b", "position", "normal", "force (N)", "penetration (m)")
        for row in rows:
            shown.add_row(row["a"], row["b"], _xyz(row["position"]), _xyz(row["normal"]),
                          f"{row['force']:.4g}", f"{row['penetration']:.3g}")
        console.print(shown)
    emit(rows, as_json, table)
