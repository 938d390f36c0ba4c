"""Command-line options shared by ``view``, ``bake`` and ``compare``: scan, material, lights, solver.

One place turns the words a user types into the API's objects, so every subcommand accepts and
rejects the same things with the same sentences:

* :func:`add_scan_options` (read by :func:`translucency.app.shading.scan.load_scan`) -- a mesh file (or
  the embedded default), its unit (inferred from the size when not given) and its up axis;
* :func:`add_light_options` / :func:`lights_from_args` -- ``--light-dir X,Y,Z`` (from the object toward
  the light), ``--light SPEC`` (any mix, see :data:`~translucency.app.lightspec.LIGHT_SPEC_HELP`),
  ``--env FILE`` (an equirectangular HDR map) with ``--env-directions N``;
* :func:`add_format_option` -- ``--format ply|vtp|vtk|glb|gltf``, the format of the files written into
  an output folder (:mod:`translucency.app.exports`);
* :func:`add_solver_options` / :func:`solver_settings` -- ``--model``, ``--method``, ``--tol``,
  ``--resolution``, ``--no-shadows``, ``--per-direction``, ``--bounces``, ``--exposure``, ``--memory-limit``,
  ``--time-limit``,
  made from and read into :class:`~translucency.app.shading.settings.ShadeSettings` (help texts, defaults, checks);
* :func:`add_quiet_option` / :func:`quiet` -- ``-q``/``--quiet``: no progress (see :mod:`translucency.app.progress`).

Every option that has a default says it in its help (``--help``).

:class:`ArgumentParser` is argparse's parser, except that a negative number or vector is taken as the
value of the option before it as written: ``--light-dir -1,0.3,-0.5`` (argparse alone reads
``-1,0.3,-0.5`` as an unknown option and asks for ``--light-dir=-1,0.3,-0.5``).
"""

from __future__ import annotations

import argparse
import dataclasses
import re
import sys

import numpy as np

from ..errors import InvalidParameterError
from ..scatter.medium import DEFAULT_ETA
from ..scatter.names import DEVICES, METHODS, MODELS

#: Help of ``--unit`` (``inspect`` has it too).
UNIT_HELP = (
    "length unit of the file: mm, cm, m, in, or mm per unit as a number (default: inferred from the size, "
    "millimetres for 5 to 5000 units across, metres for 0.005 to 5)"
)


# one number (integer, decimal, exponent, inf, nan) and a comma-separated list of them, the first negative
_NUMBER = r"(?:(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|inf(?:inity)?|nan)"
_NEGATIVE_VALUE = re.compile(rf"-{_NUMBER}(?:\s*,\s*[-+]?{_NUMBER})*", re.IGNORECASE)


#: Options whose values may start with "-" and are not numbers (``--up -z``).
NEGATIVE_VALUE_OPTIONS = ("--up",)


def join_negative_values(argv) -> list[str]:
    """``[..., "--flag", "-1,0.3,-0.5", ...]`` with each negative number or vector after an option
    joined to it (``"--flag=-1,0.3,-0.5"``), so that argparse reads it as that option's value.

    Only tokens that are numbers or comma-separated numbers are joined (``-1``, ``-0.5e3``,
    ``-1,0.3,-0.5``, ``-inf``), only right after a token that is an option without a value
    (``--light-dir``, ``-o``), and nothing after ``--``; after an option of
    :data:`NEGATIVE_VALUE_OPTIONS` any value that starts with "-" is joined (``--up -z``).
    """
    argv = [str(token) for token in argv]
    joined: list[str] = []
    for token in argv:
        previous = joined[-1] if joined else ""
        negative = _NEGATIVE_VALUE.fullmatch(token) or (previous in NEGATIVE_VALUE_OPTIONS and token.startswith("-"))
        if (
            "--" not in joined
            and negative
            and previous.startswith("-")
            and previous != "--"
            and "=" not in previous
            and not _NEGATIVE_VALUE.fullmatch(previous)
        ):
            joined[-1] = f"{previous}={token}"
        else:
            joined.append(token)
    return joined


class ArgumentParser(argparse.ArgumentParser):
    """argparse's parser that reads a negative number or vector after an option as its value
    (:func:`join_negative_values`); subcommand parsers made from it are of this class too."""

    def parse_known_args(self, args=None, namespace=None):
        """As argparse's, after :func:`join_negative_values` (``args`` default: ``sys.argv[1:]``)."""
        return super().parse_known_args(join_negative_values(sys.argv[1:] if args is None else args), namespace)

    def parse_args(self, args=None, namespace=None):
        """As argparse's, with arguments it does not know named in one sentence, with the nearest option."""
        parsed, extras = self.parse_known_args(args, namespace)
        if extras:
            self.error(unknown_arguments(extras, self._known_options(parsed)))
        return parsed

    def _known_options(self, parsed) -> list[str]:
        """The option strings of this parser and of the subcommand ``parsed`` chose."""
        known = [flag for action in self._actions for flag in action.option_strings]
        for action in self._actions:
            if isinstance(action, argparse._SubParsersAction):
                for sub in action.choices.values():
                    if getattr(parsed, "func", None) is sub.get_default("func"):
                        known += [flag for a in sub._actions for flag in a.option_strings]
        return known


def unknown_arguments(extras, known) -> str:
    """The sentence for arguments no option takes: the first unknown option with the nearest known one, or the
    first stray value."""
    import difflib

    options = [token for token in extras if token.startswith("-")]
    if options:
        token = options[0].split("=", 1)[0]
        near = difflib.get_close_matches(token, known, n=1, cutoff=0.5) or difflib.get_close_matches(
            "-" + token.lstrip("-"), known, n=1, cutoff=0.5
        )
        hint = f" (did you mean {near[0]}?)" if near else ""
        return f"unknown option {token}{hint}; --help lists the options."
    return f"unexpected argument {extras[0]!r}: no option or input takes it; --help lists the arguments."


def add_scan_options(parser: argparse.ArgumentParser, *, several: bool = False) -> None:
    """``MESH`` (optional: the embedded default scan), ``--unit`` and ``--up``."""
    from ..io.upright import UP_CHOICES

    if several:
        parser.add_argument(
            "meshes",
            nargs="*",
            metavar="MESH",
            help="mesh files (PLY, OBJ, STL, OFF, VTK, ...); none: the embedded default scan",
        )
    else:
        parser.add_argument(
            "mesh",
            nargs="?",
            metavar="MESH",
            help="mesh file (PLY, OBJ, STL, OFF, VTK, ...); none: the embedded default scan",
        )
    parser.add_argument("--unit", default=None, help=UNIT_HELP)
    parser.add_argument(
        "--up",
        default="auto",
        choices=UP_CHOICES,
        metavar="{x,y,z,-x,-y,-z,auto}",
        help="the scan's up axis, for the camera and the default light (above and in front); "
        "auto (default): the side it stands on, a flat base, else +y",
    )


def add_light_options(parser: argparse.ArgumentParser) -> None:
    """``--light-dir``, ``--light``, ``--env`` and ``--env-directions``."""
    from .lightspec import LIGHT_SPEC_HELP

    group = parser.add_argument_group(
        "lights (default: a white directional light, 1 W/m^2, above and in front of the scan by --up)"
    )
    group.add_argument(
        "--light-dir",
        metavar="X,Y,Z",
        help="direction from the object toward a white directional light of 1 W/m^2, in the scan's "
        "own frame (the file's axes, not turned by --up); any length, negative parts "
        "as written (-1,0.3,-0.5)",
    )
    group.add_argument("--light", metavar="SPEC", help=f"lights in short form: {LIGHT_SPEC_HELP}")
    group.add_argument("--env", metavar="FILE", help="equirectangular HDR environment map (.hdr), W/(m^2 sr)")
    group.add_argument(
        "--env-directions",
        type=int,
        default=256,
        metavar="N",
        help="directions sampled from the environment map (default 256)",
    )


#: The options that define a material inline (the keys of :mod:`translucency.scatter.definition`).
INLINE_MATERIAL_OPTIONS = {
    "--sigma-a": "absorption coefficient, 1/mm",
    "--sigma-s": "scattering coefficient (not reduced), 1/mm",
    "--g": "Henyey-Greenstein mean cosine (default 0)",
    "--eta": f"relative index of refraction (default {DEFAULT_ETA:g})",
    "--reflectance": "diffuse reflectance, strictly between 0 and 1",
    "--mfp": "mean free path 1/sigma_t', mm",
}


def inline_material(args):
    """The material the inline options define (a :class:`~translucency.scatter.medium.Medium` named
    ``custom-`` and six hex digits of its numbers, so that two definitions baked into one folder do not
    write the same file), or None when none is given; a wrong combination is a sentence naming the options."""
    import hashlib

    from ..scatter.definition import medium_from_definition

    given = {
        flag: getattr(args, flag[2:].replace("-", "_"), None)
        for flag in INLINE_MATERIAL_OPTIONS
        if getattr(args, flag[2:].replace("-", "_"), None) is not None
    }
    if not given:
        return None
    if not set(given) - {"--g", "--eta"}:
        raise InvalidParameterError(
            f"{' and '.join(given)} need the material they change: add --sigma-a and --sigma-s, or --reflectance "
            "and --mfp."
        )
    pairs = (("--sigma-a", "--sigma-s"), ("--reflectance", "--mfp"))
    forms = [pair for pair in pairs if set(pair) & set(given)]
    if len(forms) > 1:
        raise InvalidParameterError("give --sigma-a and --sigma-s, or --reflectance and --mfp, not both kinds.")
    missing = [flag for flag in forms[0] if flag not in given]
    if missing:
        raise InvalidParameterError(f"{forms[0][0]} and {forms[0][1]} go together: add {missing[0]}.")
    definition = {}
    for flag, text in given.items():
        try:
            values = [float(part) for part in str(text).split(",")]
        except ValueError:
            values = []
        single = flag in ("--g", "--eta")
        if len(values) not in ((1,) if single else (1, 3)):
            shape = "one number" if single else "one number or three numbers R,G,B"
            raise InvalidParameterError(f"{flag} must be {shape}, got {text!r}.")
        definition[flag[2:].replace("-", "_")] = values[0] if len(values) == 1 else values
    digest = hashlib.sha1(repr(sorted(definition.items())).encode()).hexdigest()[:6]
    return medium_from_definition({**definition, "name": f"custom-{digest}"}, "the material options")


def add_solver_options(parser: argparse.ArgumentParser) -> None:
    """``--material`` and the solver's settings (help texts and defaults: :mod:`translucency.app.shading.settings`)."""
    from .shading.settings import HELP, ShadeSettings

    default = {field.name: field for field in dataclasses.fields(ShadeSettings)}
    group = parser.add_argument_group("material and solver")
    group.add_argument(
        "--material",
        default=None,  # None: the record's default, and the material options may name the material instead
        help=f"{HELP['material']} (default {default['material'].default})",
    )
    inline = parser.add_argument_group(
        "material by its numbers (instead of --material; docs/physics.md 6.4)",
        "either --sigma-a and --sigma-s, or --reflectance and --mfp; one number or R,G,B each",
    )
    for flag, text in INLINE_MATERIAL_OPTIONS.items():
        inline.add_argument(flag, metavar="G" if flag == "--g" else "N" if flag == "--eta" else "R,G,B", help=text)
    group.add_argument(
        "--model",
        default=default["model"].default,
        choices=MODELS,
        help=f"{HELP['model']} (default {default['model'].default})",
    )
    group.add_argument(
        "--method",
        default=default["method"].default,
        choices=METHODS,
        help=f"{HELP['method']} (default {default['method'].default})",
    )
    group.add_argument(
        "--device",
        default=default["device"].default,
        choices=DEVICES,
        help=f"{HELP['device']} (default {default['device'].default})",
    )
    group.add_argument(
        "--tol", type=float, default=default["tol"].default, help=f"{HELP['tol']} (default {default['tol'].default:g})"
    )
    group.add_argument(
        "--resolution", default=default["resolution"].default, help=f"{HELP['resolution']} (default %(default)s)"
    )
    group.add_argument("--no-shadows", action="store_true", help=HELP["shadows"])
    group.add_argument("--per-direction", action="store_true", help=HELP["per_direction"])
    group.add_argument("--albedo-from-colors", action="store_true", help=HELP["albedo"])
    group.add_argument(
        "--bounces",
        type=whole_number,
        default=default["bounces"].default,
        metavar="N",
        help=f"{HELP['bounces']} (default {default['bounces'].default})",
    )
    group.add_argument("--exposure", type=float, default=None, help=HELP["exposure"])
    group.add_argument("--memory-limit", type=float, default=None, metavar="GB", help=HELP["memory_limit"])
    group.add_argument(
        "--time-limit",
        type=float,
        default=None,
        metavar="S",
        help=f"{HELP['time_limit']} (default {default['time_limit'].default:g})",
    )


def whole_number(text: str):
    """``text`` as an int when it spells one, else unchanged (the setting's own check then refuses it
    with its sentence, rather than argparse with its own)."""
    try:
        return int(text)
    except ValueError:
        return text


def add_quiet_option(parser: argparse.ArgumentParser) -> None:
    """``-q``/``--quiet``: no progress bars or lines (warnings, errors and results still print).

    Left out of the namespace when not given (read it with :func:`quiet`), so that ``translucency -q
    bake`` and ``translucency bake -q`` both work.
    """
    parser.add_argument(
        "-q",
        "--quiet",
        action="store_true",
        default=argparse.SUPPRESS,
        help="no progress bars or progress lines (warnings, errors and results still print)",
    )


def quiet(args) -> bool:
    """True when ``-q``/``--quiet`` was given (:func:`add_quiet_option`)."""
    return bool(getattr(args, "quiet", False))


def add_format_option(parser: argparse.ArgumentParser) -> None:
    """``--format``: the format of the files written into an output folder (default ply; None when not given,
    so a file output's suffix can name its own)."""
    from ..io.baked import BAKED_FORMATS
    from .exports import FORMAT_HELP

    parser.add_argument("--format", default=None, choices=BAKED_FORMATS, help=FORMAT_HELP)


def add_preview_option(parser: argparse.ArgumentParser) -> None:
    """``--preview``: a labelled picture beside each output (:mod:`translucency.app.figure`)."""
    parser.add_argument(
        "--preview",
        action="store_true",
        help="also write <stem>_<material>.png beside each output: the sRGB view and the false-colour "
        "luminance in W/(m^2 sr) per W/m^2 side by side, with colour bar, scale bar and the light's arrow",
    )


def parse_vector(text: str, name: str) -> np.ndarray:
    """Three finite numbers from ``"x,y,z"``; ``name`` is the option, for the error sentence."""
    try:
        values = np.array([float(part) for part in str(text).split(",")], dtype=np.float64)
    except ValueError:
        values = np.array([])
    if values.shape != (3,) or not np.all(np.isfinite(values)):
        raise InvalidParameterError(f"{name} must be three finite numbers x,y,z (e.g. 0,1,0.5), got {text!r}.")
    if not np.any(values):
        raise InvalidParameterError(f"{name} must not be the zero vector, got {text!r}.")
    return values


def lights_from_args(args) -> tuple | None:
    """The lights the options describe (several options add up); None when none is given (the
    pipeline then places its default light by the scan's up axis)."""
    from ..scatter.lights import DirectionalLight
    from .lightspec import parse_light_spec

    lights = []
    if getattr(args, "light_dir", None) is not None:
        lights.append(DirectionalLight(parse_vector(args.light_dir, "--light-dir"), 1.0))
    if getattr(args, "light", None) is not None:
        lights.extend(parse_light_spec(args.light))
    if getattr(args, "env", None):
        from .environment import load_environment

        lights.append(load_environment(args.env, n_directions=args.env_directions))
    return tuple(lights) or None


def solver_settings(args, **changes):
    """The :class:`~translucency.app.shading.settings.ShadeSettings` the options describe (``changes`` replace
    fields before the check, e.g. ``resolution="full"``); a bad value is a sentence naming its flag."""
    from ..errors import command_line_spelling
    from .shading.settings import ShadeSettings

    custom = inline_material(args)
    if custom is not None and args.material is not None:
        raise InvalidParameterError(
            f"give --material {args.material} or the material's numbers (--reflectance and --mfp, or --sigma-a and "
            "--sigma-s), not both."
        )
    fields = {
        "model": args.model,
        "method": args.method,
        "device": args.device,
        "tol": args.tol,
        "resolution": args.resolution,
        "shadows": not args.no_shadows,
        "per_direction": args.per_direction,
        "bounces": args.bounces,
        "albedo": "vertex_colors" if getattr(args, "albedo_from_colors", False) else "material",
        "exposure": args.exposure,
        "memory_limit": args.memory_limit,
        "up": getattr(args, "up", "auto"),
    }
    if args.time_limit is not None:  # else the record's own default
        fields["time_limit"] = args.time_limit
    if custom is not None or args.material is not None:  # else the record's own default
        fields["material"] = args.material if custom is None else custom
    with command_line_spelling():
        return ShadeSettings(**{**fields, **changes})
