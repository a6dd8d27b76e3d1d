"""Writes the binary assets of the test scenes (run once; the outputs are
committed): a PLY mesh by Mitsuba's own writer and a PNG texture by Pillow.

    python3 tests/data/scenes/make_assets.py
"""

from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


def blob_vertices_faces(n_lon=16, n_lat=8, bumps=0.15):
    """A bumpy sphere of radius about 1 (vertices, triangles)."""
    theta = np.linspace(0.0, np.pi, n_lat + 1)[:, None]
    phi = np.linspace(0.0, 2 * np.pi, n_lon + 1)[None, :-1]
    r = 1.0 + bumps * np.sin(3 * phi) * np.sin(theta) ** 2
    v = np.stack(np.broadcast_arrays(r * np.sin(theta) * np.cos(phi), r * np.cos(theta) + 0 * phi,
                                     r * np.sin(theta) * np.sin(phi)), axis=-1).reshape(-1, 3)
    faces = []
    for i in range(n_lat):
        for j in range(n_lon):
            a, b = i * n_lon + j, i * n_lon + (j + 1) % n_lon
            c, d = a + n_lon, b + n_lon
            if i > 0:
                faces.append((a, b, c))
            if i < n_lat - 1:
                faces.append((b, d, c))
    return v.astype(np.float32), np.array(faces, dtype=np.uint32)


def write_ply(path: Path, vertices, faces) -> None:
    """A PLY written by Mitsuba (``Mesh.write_ply``)."""
    import mitsuba as mi

    if mi.variant() is None:
        mi.set_variant("scalar_rgb")
    mesh = mi.Mesh("blob", len(vertices), len(faces))
    params = mi.traverse(mesh)
    params["vertex_positions"] = np.ravel(vertices)
    params["faces"] = np.ravel(faces)
    params.update()
    path.parent.mkdir(parents=True, exist_ok=True)
    mesh.write_ply(str(path))


def write_checker(path: Path, colours=((200, 60, 40), (240, 230, 200)), n=16, cell=2) -> None:
    from PIL import Image

    y, x = np.mgrid[0:n, 0:n]
    mask = ((x // cell + y // cell) % 2).astype(bool)
    img = np.where(mask[..., None], np.array(colours[1], np.uint8), np.array(colours[0], np.uint8))
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(img.astype(np.uint8)).save(path)


if __name__ == "__main__":
    write_ply(HERE / "tabletop" / "meshes" / "blob.ply", *blob_vertices_faces())
    write_checker(HERE / "tabletop" / "textures" / "checker.png")
