"""Three materials on the embedded default scan, one image: marble, skim milk and ketchup side by side.

    python examples/compare_materials.py OUT [--quick]

Writes OUT/grid.png (one exposure for all three, so brightness compares), OUT/profile.png and the
statistics (CSV, JSON), and prints the mean radiance of each over the lit vertices.
"""

import argparse

import translucency as tl


def default_scan(quick: bool):
    """The embedded default scan, cleaned (mm); decimated to about 2,000 vertices with ``quick``."""
    mesh, _ = tl.clean_mesh(tl.load_default_scan())
    return tl.decimate_mesh(mesh, target_faces=4000).proxy if quick else mesh


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("output", help="output folder (created)")
    parser.add_argument("--quick", action="store_true", help="a decimated scan and small images (a few seconds)")
    args = parser.parse_args()

    result = tl.compare(
        default_scan(args.quick),
        ["marble", "skim_milk", "ketchup"],
        output=args.output,
        cell_size=(240, 240) if args.quick else (480, 480),
    )
    for material in result.materials:
        r, g, b = result.mean(material, "directional")
        print(f"{material:<10} mean radiance over lit vertices R {r:.4f} G {g:.4f} B {b:.4f} W/(m^2 sr) per W/m^2")
    print(f"wrote {result.files['grid']}")


if __name__ == "__main__":
    main()
