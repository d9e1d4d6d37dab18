"""An independent reference for the media furnace scenes: a homogeneous sphere in a uniform
environment, computed by an analog random walk (numpy), not by lightfarm's code:

    python3 tools/media_reference.py tests/scenes/media/furnace_albedo.json [--walks 4000000]
    python3 tools/media_reference.py --check     checks the walk against closed forms

The scene must be one sphere whose interior is a homogeneous medium with grey sigma_a, sigma_s
(m^-1, times its scale) and Henyey-Greenstein g, a uniform environment of radiance E and a
perspective camera with the box filter. Camera rays are drawn as the renderer draws them
(uniform over the film); a ray that misses the sphere sees E, one that enters it walks: free
paths ~ Exp(sigma_t), at each collision the walk survives with the albedo sigma_s / sigma_t
(estimated as albedo^collisions) and turns by the HG phase function, until it leaves the
sphere and sees E. Prints the image's mean and its centre pixels' mean with standard errors.
"""

import json
import math
import sys

import numpy as np


def fail(message):
    sys.exit(f"media_reference.py: {message}")


def load(path):
    with open(path) as f:
        scene = json.load(f)
    spheres = [s for s in scene["shapes"] if s["type"] == "sphere"]
    if len(spheres) != 1 or len(scene["shapes"]) != 1 or "interior" not in spheres[0]:
        fail("expected exactly one shape, a sphere with an interior medium")
    medium = scene["media"][spheres[0]["interior"]]
    if medium["type"] != "homogeneous":
        fail("the sphere's medium must be homogeneous")
    scale = medium.get("scale", 1.0)
    sigma_a, sigma_s = set(medium.get("sigma_a", [0] * 3)), set(medium.get("sigma_s", [0] * 3))
    if len(sigma_a) != 1 or len(sigma_s) != 1:
        fail("sigma_a and sigma_s must be grey (one value for r, g, b)")
    env = [l for l in scene.get("lights", []) if l["type"] == "environment"]
    if len(scene.get("lights", [])) != 1 or len(env) != 1 or len(set(env[0]["radiance"])) != 1:
        fail("expected one light, a uniform grey environment given by radiance [E, E, E]")
    camera = scene["camera"]
    if camera.get("type", "perspective") != "perspective" or "filter" in camera:
        fail("expected a perspective camera with the box filter")
    return {
        "center": np.array(spheres[0]["center"], float), "radius": float(spheres[0]["radius"]),
        "sigma_a": sigma_a.pop() * scale, "sigma_s": sigma_s.pop() * scale,
        "g": float(medium.get("g", 0.0)), "radiance": float(env[0]["radiance"][0]),
        "camera": camera,
    }


def camera_rays(camera, n, rng, centre_only):
    """Ray directions drawn uniformly over the film (or over its centre 2 x 2 pixels)."""
    w, h = camera["resolution"]
    eye = np.array(camera["position"], float)
    f = np.array(camera["look_at"], float) - eye
    f /= np.linalg.norm(f)
    r = np.cross(f, np.array(camera.get("up", [0, 1, 0]), float))
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    t = math.tan(math.radians(camera["fov_y_deg"]) / 2)
    if centre_only:
        fx = (w / 2 - 1 + 2 * rng.random(n)) / w
        fy = (h / 2 - 1 + 2 * rng.random(n)) / h
    else:
        fx, fy = rng.random(n), rng.random(n)
    x = (2 * fx - 1) * t * w / h
    y = (1 - 2 * fy) * t
    d = f[None, :] + x[:, None] * r[None, :] + y[:, None] * u[None, :]
    return np.broadcast_to(eye, d.shape).copy(), d / np.linalg.norm(d, axis=1)[:, None]


def sphere_exit(p, d, c, radius):
    """Distance along d from p (inside the sphere) to its surface."""
    oc = p - c
    b = np.einsum("ij,ij->i", oc, d)
    disc = b * b - (np.einsum("ij,ij->i", oc, oc) - radius * radius)
    return -b + np.sqrt(np.maximum(disc, 0))


def hg_turn(d, g, rng):
    """New directions, at HG-distributed angles to d (g > 0: forward)."""
    n = len(d)
    xi = rng.random(n)
    if abs(g) < 1e-3:
        cos = 1 - 2 * xi
    else:
        s = (1 - g * g) / (1 - g + 2 * g * xi)
        cos = (1 + g * g - s * s) / (2 * g)
    sin = np.sqrt(np.maximum(0, 1 - cos * cos))
    phi = 2 * math.pi * rng.random(n)
    # An orthonormal frame around d (Duff et al. 2017).
    sign = np.where(d[:, 2] >= 0, 1.0, -1.0)
    a = -1 / (sign + d[:, 2])
    b = d[:, 0] * d[:, 1] * a
    t1 = np.stack([1 + sign * d[:, 0] ** 2 * a, sign * b, -sign * d[:, 0]], axis=1)
    t2 = np.stack([b, sign + d[:, 1] ** 2 * a, -d[:, 1]], axis=1)
    return (sin * np.cos(phi))[:, None] * t1 + (sin * np.sin(phi))[:, None] * t2 + cos[:, None] * d


def estimate(s, n, rng, centre_only):
    p, d = camera_rays(s["camera"], n, rng, centre_only)
    c, radius = s["center"], s["radius"]
    sigma_t = s["sigma_a"] + s["sigma_s"]
    albedo = s["sigma_s"] / sigma_t if sigma_t > 0 else 1.0
    value = np.full(n, s["radiance"])
    # Entry: the nearest intersection in front of the camera.
    oc = p - c
    b = np.einsum("ij,ij->i", oc, d)
    disc = b * b - (np.einsum("ij,ij->i", oc, oc) - radius * radius)
    hit = (disc > 0) & (-b - np.sqrt(np.maximum(disc, 0)) > 0)
    idx = np.nonzero(hit)[0]
    p = p[idx] + (-b[idx] - np.sqrt(disc[idx]))[:, None] * d[idx]
    d = d[idx]
    weight = np.ones(len(idx))
    while len(idx) and sigma_t > 0:
        free = -np.log(1 - rng.random(len(idx))) / sigma_t
        leave = free >= sphere_exit(p, d, c, radius)
        value[idx[leave]] = weight[leave] * s["radiance"]
        keep = ~leave
        idx, p, d, free, weight = idx[keep], p[keep], d[keep], free[keep], weight[keep]
        p = p + free[:, None] * d
        weight = weight * albedo
        d = hg_turn(d, s["g"], rng)
        # Walks whose weight no longer matters (below 1e-12 of E) are dropped, a bias below it.
        alive = weight > 1e-12
        value[idx[~alive]] = 0
        idx, p, d, weight = idx[alive], p[alive], d[alive], weight[alive]
    return value.mean(), value.std() / math.sqrt(n)


def self_check():
    """Checks the walk against closed forms; exits non-zero if one fails."""
    rng = np.random.default_rng(1)
    camera = {"position": [0, 0, 4], "look_at": [0, 0, 0], "fov_y_deg": 0.01,
              "resolution": [2, 2]}
    sphere = {"center": np.zeros(3), "radius": 1.0, "g": 0.5, "radiance": 1.0, "camera": camera}
    failed = []
    # No scattering: the axial ray's transmittance exp(-sigma_a * 2R).
    mean, error = estimate({**sphere, "sigma_a": 1.0, "sigma_s": 0.0}, 2_000_000, rng, False)
    if abs(mean - math.exp(-2)) > 4 * error:
        failed.append(f"absorber: {mean:.5f} +- {error:.5f}, expected {math.exp(-2):.5f}")
    # No absorption: every walk leaves with its weight 1.
    mean, error = estimate({**sphere, "sigma_a": 0.0, "sigma_s": 4.0}, 100_000, rng, False)
    if mean != 1.0:
        failed.append(f"furnace: {mean}, expected exactly 1")
    # HG's mean cosine is g.
    d = rng.normal(size=(400_000, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    for g in (-0.3, 0.0, 0.7):
        cos = np.einsum("ij,ij->i", hg_turn(d, g, rng), d)
        if abs(cos.mean() - g) > 4 * cos.std() / math.sqrt(len(cos)):
            failed.append(f"HG g={g}: mean cosine {cos.mean():.5f}")
    print("media_reference.py --check: " + ("; ".join(failed) if failed else "all passed"))
    sys.exit(1 if failed else 0)


def main():
    args = sys.argv[1:]
    if args == ["--check"]:
        self_check()
    walks = 4_000_000
    if "--walks" in args:
        i = args.index("--walks")
        walks = int(args[i + 1])
        del args[i : i + 2]
    if len(args) != 1:
        sys.exit(__doc__)
    s = load(args[0])
    rng = np.random.default_rng(20261129)
    print(f"{args[0]}: sigma_a {s['sigma_a']:g}, sigma_s {s['sigma_s']:g}, g {s['g']:g}, "
          f"sphere radius {s['radius']:g}, environment {s['radiance']:g}, {walks} walks each")
    for centre_only, what in ((False, "image mean"), (True, "centre 2x2 pixels mean")):
        sums = [estimate(s, 500_000, rng, centre_only) for _ in range(max(1, walks // 500_000))]
        mean = float(np.mean([m for m, _ in sums]))
        error = math.sqrt(sum(e * e for _, e in sums)) / len(sums)
        print(f"  {what}: {mean:.5f} +- {error:.5f} (1 sigma)")


if __name__ == "__main__":
    main()
