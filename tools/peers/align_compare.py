"""mint align against Open3D's sequential point-to-plane ICP from the same
perturbed starts, on a Stanford scan set (.conf), for scripts/bench/align_peers.sh.

Usage: align_compare.py MINT SET.conf DEG MM SEEDS [MAX_DIST_MM]
           [--first-seed N] [--no-icp] [--agreement MM[,MM...]]

For each seed: every scan but the first is moved by DEG degrees about a random
axis through the model's centre and by MM millimetres in a random direction
(numpy's generator, seeded), written as a start .conf; `mint align` and
Open3D (each scan in file order registered to the union of the scans before
it, point to plane, correspondences within MAX_DIST_MM, default 2) run from
it. Each result is measured as the issue measures it: every scan's pose
relative to the first, against the same in the original .conf: the rotation
angle and the displacement of the model's centre. One line per seed and tool:
worst degrees, worst mm, seconds.

--agreement MM,...: also how well the scans agree under each pose set, by
Open3D's `evaluate_registration` (not mint's code): for every two scans, both
ways, the inlier RMSE of the points within MM mm of the other scan's nearest
point; a pair overlaps when at least 5% of each scan's points are inliers
(mint align's --min-overlap default), and its RMSE pools both directions.
Printed: the median over overlapping pairs and their count, for the .conf
once and for each mint result. At the end: the spread of mint's results
(the worst pose difference, relative to scan 0, between any two starts),
the scans flagged as failed, and mint's own agreement figure (`mint align
--json`, "agreement").
--no-icp: mint only (no Open3D ICP from the starts).

.conf poses: `bmesh FILE tx ty tz qx qy qz qw` means p_world = R(q)^T p + t
(see crates/mint-range/src/scanset.rs)."""
import json, os, subprocess, sys, tempfile, time
import numpy as np


def quat_to_r(q):
    x, y, z, w = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def r_to_quat(r):
    # Shepperd's method.
    t = np.trace(r)
    if t > 0:
        s = np.sqrt(t + 1.0) * 2
        return np.array([(r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s, 0.25 * s])
    i = int(np.argmax(np.diag(r)))
    j, k = (i + 1) % 3, (i + 2) % 3
    s = np.sqrt(1.0 + r[i, i] - r[j, j] - r[k, k]) * 2
    q = np.zeros(4)
    q[i] = 0.25 * s
    q[j] = (r[j, i] + r[i, j]) / s
    q[k] = (r[k, i] + r[i, k]) / s
    q[3] = (r[k, j] - r[j, k]) / s
    return q


def read_conf(path):
    """Returns the other lines and the scans: (file, 4x4 scan-to-world)."""
    other, scans = [], []
    for line in open(path):
        tok = line.split()
        if tok and tok[0] == "bmesh":
            t = np.array([float(v) for v in tok[2:5]])
            q = np.array([float(v) for v in tok[5:9]])
            m = np.eye(4)
            m[:3, :3] = quat_to_r(q / np.linalg.norm(q)).T
            m[:3, 3] = t
            scans.append((tok[1], m))
        elif tok:
            other.append(line.rstrip("\n"))
    return other, scans


def write_conf(path, other, scans):
    with open(path, "w") as f:
        for line in other:
            f.write(line + "\n")
        for name, m in scans:
            q = r_to_quat(m[:3, :3].T)
            t = m[:3, 3]
            f.write("bmesh " + name + " " + " ".join(repr(float(v)) for v in (*t, *q)) + "\n")


def rotation(axis, deg):
    a = np.radians(deg)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(a) * k + (1 - np.cos(a)) * k @ k


def unit(rng):
    while True:
        v = rng.uniform(-1, 1, 3)
        n = np.linalg.norm(v)
        if 1e-3 < n <= 1:
            return v / n


def errors(truth, got, center):
    """Worst (degrees, metres) over scans of the pose relative to scan 0."""
    worst = (0.0, 0.0)
    for i in range(len(truth)):
        rel_t = np.linalg.inv(truth[0]) @ truth[i]
        rel_g = np.linalg.inv(got[0]) @ got[i]
        d = np.linalg.inv(rel_t) @ rel_g
        ang = np.degrees(np.arccos(np.clip((np.trace(d[:3, :3]) - 1) / 2, -1, 1)))
        c = np.linalg.inv(rel_t) @ np.linalg.inv(truth[0]) @ np.append(center, 1)
        disp = np.linalg.norm((rel_t @ c)[:3] - (rel_g @ c)[:3])
        worst = (max(worst[0], ang), max(worst[1], disp))
    return worst


def open3d_sequential(o3d, folder, scans, max_dist):
    clouds = []
    for name, m in scans:
        pc = o3d.io.read_point_cloud(os.path.join(folder, name))
        pc.transform(m)
        clouds.append(pc)
    out = [scans[0][1]]
    model = o3d.geometry.PointCloud(clouds[0])
    for i in range(1, len(clouds)):
        model.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=4 * max_dist, max_nn=30))
        res = o3d.pipelines.registration.registration_icp(
            clouds[i], model, max_dist, np.eye(4),
            o3d.pipelines.registration.TransformationEstimationPointToPlane(),
            o3d.pipelines.registration.ICPConvergenceCriteria(max_iteration=200))
        clouds[i].transform(res.transformation)
        out.append(res.transformation @ scans[i][1])
        model += clouds[i]
        model = model.voxel_down_sample(max_dist / 4)
    return out


def agreement(o3d, clouds, poses, threshold, min_fitness=0.05):
    """(median inlier RMSE over overlapping pairs, pairs) under `poses`."""
    moved = []
    for pc, m in zip(clouds, poses):
        c = o3d.geometry.PointCloud(pc)
        c.transform(m)
        moved.append(c)
    rmse = []
    ev = o3d.pipelines.registration.evaluate_registration
    for i in range(len(moved)):
        for j in range(i + 1, len(moved)):
            a = ev(moved[i], moved[j], threshold, np.eye(4))
            b = ev(moved[j], moved[i], threshold, np.eye(4))
            if min(a.fitness, b.fitness) < min_fitness:
                continue
            na, nb = a.fitness * len(moved[i].points), b.fitness * len(moved[j].points)
            rmse.append(np.sqrt((a.inlier_rmse ** 2 * na + b.inlier_rmse ** 2 * nb) / (na + nb)))
    return (float(np.median(rmse)) if rmse else float("nan"), len(rmse))


def spread(results, center):
    """Worst (degrees, metres) between any two results, relative to scan 0."""
    worst = (0.0, 0.0)
    for a in range(len(results)):
        for b in range(a + 1, len(results)):
            e = errors(results[a], results[b], center)
            worst = (max(worst[0], e[0]), max(worst[1], e[1]))
    return worst


def main():
    args = sys.argv[1:]
    def flag(name, default=None, has_value=True):
        if name not in args:
            return default
        i = args.index(name)
        v = args[i + 1] if has_value else True
        del args[i:i + (2 if has_value else 1)]
        return v
    first = int(flag("--first-seed", "0"))
    no_icp = flag("--no-icp", False, has_value=False)
    thresholds = [float(v) * 1e-3 for v in flag("--agreement", "").split(",") if v]
    mint, conf, deg, mm, seeds = args[0], args[1], float(args[2]), float(args[3]), int(args[4])
    max_dist = (float(args[5]) if len(args) > 5 else 2.0) * 1e-3
    try:
        import open3d as o3d
    except Exception as e:  # noqa: BLE001 - any import failure means "not available"
        o3d = None
        print(f"open3d not available: {e}")
    folder = os.path.dirname(os.path.abspath(conf))
    other, scans = read_conf(conf)
    truth = [m for _, m in scans]
    # The model's centre: the mean of the scans' bounding-box centres in the world.
    centers = []
    for name, m in scans:
        if o3d is not None:
            pts = np.asarray(o3d.io.read_point_cloud(os.path.join(folder, name)).points)
            c = 0.5 * (pts.min(0) + pts.max(0))
        else:
            c = np.zeros(3)
        centers.append((m @ np.append(c, 1))[:3])
    center = np.mean(centers, axis=0)
    clouds = [o3d.io.read_point_cloud(os.path.join(folder, name)) for name, _ in scans] if (o3d is not None and thresholds) else []
    if thresholds and o3d is None:
        sys.exit("--agreement needs open3d")
    if clouds:
        for th in thresholds:
            med, n = agreement(o3d, clouds, truth, th)
            print(f".conf        agreement at {th * 1e3:g} mm: median inlier RMSE {med * 1e3:.4f} mm over {n} pairs")
    results, flagged, ours = [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        for name, _ in scans:
            os.symlink(os.path.join(folder, name), os.path.join(tmp, name))
        for seed in range(first, first + seeds):
            rng = np.random.default_rng(1000 + seed)
            start = [scans[0]]
            for name, m in scans[1:]:
                r = rotation(unit(rng), deg)
                mv = np.eye(4)
                mv[:3, :3] = r
                mv[:3, 3] = center - r @ center + unit(rng) * mm * 1e-3
                start.append((name, mv @ m))
            sp = os.path.join(tmp, f"start{seed}.conf")
            write_conf(sp, other, start)
            e0 = errors(truth, [m for _, m in start], center)
            print(f"seed {seed}  start        {e0[0]:7.3f}° {e0[1] * 1e3:7.3f} mm")
            out = os.path.join(tmp, f"mint{seed}.conf")
            t = time.time()
            r = subprocess.run([mint, "align", sp, out, "--json"], capture_output=True, text=True)
            if r.returncode != 0:
                sys.exit(f"mint align failed: {r.stderr.strip()}")
            dt = time.time() - t
            j = json.loads(r.stdout)
            got = [m for _, m in read_conf(out)[1]]
            results.append(got)
            flagged.extend(f"seed {seed}: {n}" for n in j["failed"])
            ours.append(j["agreement"]["rms"])
            e = errors(truth, got, center)
            retried = [f"{s['name']} ({s['retries']})" for s in j["scans"] if s.get("retried_from")]
            print(f"seed {seed}  mint align   {e[0]:7.3f}° {e[1] * 1e3:7.3f} mm  {dt:6.1f} s  failed {len(j['failed'])}"
                  f"  mint agreement rms {j['agreement']['rms'] * 1e3:.4f} mm{'  retried: ' + ', '.join(retried) if retried else ''}")
            for th in thresholds:
                med, n = agreement(o3d, clouds, got, th)
                print(f"seed {seed}  mint align   agreement at {th * 1e3:g} mm: median inlier RMSE {med * 1e3:.4f} mm over {n} pairs")
            if o3d is not None and not no_icp:
                t = time.time()
                got = open3d_sequential(o3d, tmp, start, max_dist)
                dt = time.time() - t
                e = errors(truth, got, center)
                print(f"seed {seed}  open3d icp   {e[0]:7.3f}° {e[1] * 1e3:7.3f} mm  {dt:6.1f} s")
            sys.stdout.flush()
    sp = spread(results, center)
    print(f"mint: {len(results)} starts, spread between starts {sp[0]:.4f}° {sp[1] * 1e3:.4f} mm; scans failed: {len(flagged)} {flagged}; "
          f"mint's own agreement rms {min(ours) * 1e3:.4f}-{max(ours) * 1e3:.4f} mm")


if __name__ == "__main__":
    main()
