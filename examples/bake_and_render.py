"""Bake a scan in one material and render it: the whole chain in a few lines.

    python examples/bake_and_render.py OUT [--material NAME] [--quick]

Shades the embedded default scan under a light from the upper left with Embree shadows, writes the bake
(OUT/<material>.ply: radiance, B and display colours per vertex, every setting in the header) and a
picture of it (OUT/<material>.png), then reads the bake back.
"""

import argparse
from pathlib import Path

import translucency as tl


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("output", help="output folder (created)")
    parser.add_argument("--material", default="skin1", help="catalogue name (default skin1)")
    parser.add_argument("--quick", action="store_true", help="a decimated scan and a small image (a few seconds)")
    args = parser.parse_args()
    output = Path(args.output)
    output.mkdir(parents=True, exist_ok=True)

    mesh, _ = tl.clean_mesh(tl.load_default_scan())  # 155 mm across
    if args.quick:
        mesh = tl.decimate_mesh(mesh, target_faces=4000).proxy
    light = tl.DirectionalLight((-0.6, 0.8, 0.4), 1.0)  # from the object toward the light; E = 1 W/m^2
    settings = tl.ShadeSettings(args.material)  # method auto (tree for one light) at 1 % per vertex; every default once
    result = tl.shade_scan(mesh, settings, light)
    print(f"solved {mesh.n_points} vertices in {sum(result.timings.values()):.2f} s")

    ply = tl.write_result(result, output / f"{args.material}.ply")
    png = output / f"{args.material}.png"
    tl.render_colors(mesh, result.colors, png, window_size=(320, 320) if args.quick else (800, 800))

    baked = tl.read_baked_ply(ply)
    print(
        f"wrote {ply} ({baked.metadata['material']}, {baked.metadata['model']} dipole, "
        f"exposure {baked.metadata['exposure']:.3g}) and {png}"
    )


if __name__ == "__main__":
    main()
