"""Bring your own clustering: two clusterings written in a few lines of numpy (a spatial grid of
triangle centroids, and k-means on the centroids), measured beside meshoptimizer and k-medoids.

    python compare.py [MESH] [--out DIR]

MESH is a mesh file or a generated mesh (default gen:knot-tube). Prints a table of the metrics
`meshletlab stats` reports and writes DIR/compare.png (headless: matplotlib's Agg backend).
"""

import argparse
import pathlib

import numpy as np

import meshletlab

LIMITS = (64, 126)


def centroids(mesh):
    return mesh.positions[mesh.indices].mean(axis=1)


def grid(mesh, per_cluster=80):
    """Cubic cells sized so that a flat piece of surface through one holds about `per_cluster`
    triangles (cell side from the mean triangle area)."""
    p = mesh.positions[mesh.indices].astype(np.float64)
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    side = np.sqrt(area.mean() * per_cluster)
    c = p.mean(axis=1)
    ijk = ((c - c.min(axis=0)) / side).astype(np.int64)
    dims = ijk.max(axis=0) + 1
    return (ijk[:, 0] * dims[1] + ijk[:, 1]) * dims[2] + ijk[:, 2]


def kmeans(mesh, per_cluster=80, iterations=10, seed=1):
    """Lloyd's k-means on the centroids, k = triangles / per_cluster, seeded at random triangles."""
    c = centroids(mesh).astype(np.float64)
    k = max(1, len(c) // per_cluster)
    centres = c[np.random.default_rng(seed).choice(len(c), k, replace=False)]
    for _ in range(iterations):
        # |a - b|^2 = |a|^2 - 2 a.b + |b|^2, in blocks to bound memory on large meshes.
        labels = np.concatenate([
            np.argmin((centres**2).sum(1) - 2 * block @ centres.T, axis=1)
            for block in np.array_split(c, max(1, len(c) // 8192))
        ])
        sums = np.zeros_like(centres)
        np.add.at(sums, labels, c)
        counts = np.bincount(labels, minlength=k)[:, None]
        centres = np.where(counts > 0, sums / np.maximum(counts, 1), centres)
    return labels


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mesh", nargs="?", default="gen:knot-tube")
    ap.add_argument("--out", type=pathlib.Path, default=pathlib.Path("."))
    args = ap.parse_args()

    mesh = meshletlab.load(args.mesh)
    rows = {}
    for strategy in ("meshopt", "kmedoids"):
        ml = meshletlab.build(mesh, strategy, limits=LIMITS)
        rows[strategy] = meshletlab.metrics(mesh, ml)
    for name, labels in (("numpy grid", grid(mesh)), ("numpy k-means", kmeans(mesh))):
        # A cell or cluster over the limits is divided by meshoptimizer, as `stats --split` does.
        ml = meshletlab.from_labels(mesh, labels, split=True, limits=LIMITS)
        meshletlab.validate(mesh, ml)
        rows[name] = meshletlab.metrics(mesh, ml)
        rows[name]["split"] = f"{ml.split_clusters}/{ml.clusters}"

    columns = [
        ("meshlets", "meshlets", "{:d}"),
        ("vertex fill", "vertex_fill", "{:.3f}"),
        ("triangle fill", "primitive_fill", "{:.3f}"),
        ("radius/diag", "mean_radius_rel", "{:.4f}"),
        ("cone cullable", "cone_cullable", "{:.3f}"),
        ("connected", "connected", "{:.3f}"),
        ("split", "split", "{}"),
    ]
    print(f"{mesh.name}: {mesh.triangle_count} triangles, limits {LIMITS[0]}/{LIMITS[1]}")
    print(f"{'':>14}" + "".join(f"{h:>15}" for h, _, _ in columns))
    for name, m in rows.items():
        cells = [f.format(m[k]) if k in m else "-" for _, k, f in columns]
        print(f"{name:>14}" + "".join(f"{c:>15}" for c in cells))

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    shown = [c for c in columns if c[1] not in ("cone_cullable", "split")]
    fig, axes = plt.subplots(1, len(shown), figsize=(3.2 * len(shown), 3.2))
    for ax, (title, key, _) in zip(axes, shown):
        ax.bar(range(len(rows)), [m[key] for m in rows.values()], color="C0")
        ax.set_xticks(range(len(rows)), list(rows), rotation=45, ha="right")
        ax.set_title(title)
    fig.suptitle(f"{mesh.name}, limits {LIMITS[0]}/{LIMITS[1]}")
    fig.tight_layout()
    args.out.mkdir(parents=True, exist_ok=True)
    out = args.out / "compare.png"
    fig.savefig(out, dpi=100)
    print(f"plot: {out}")


if __name__ == "__main__":
    main()
