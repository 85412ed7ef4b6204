"""Formats the outputs of scripts/bench (in the directory given) as BENCHMARKS.md."""
import json
import platform
import subprocess
import sys


def medians(path):
    data = json.load(open(path))
    out = {}
    for b in data["benchmarks"]:
        if b.get("aggregate_name") == "median":
            out[b["run_name"]] = b["real_time"] * {"ns": 1e-3, "us": 1.0, "ms": 1e3, "s": 1e6}[b["time_unit"]]  # in us
    return data["context"], out


def cpu_model():
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def load_section():
    """The load benchmark's section, from docs/load/ (scripts/bench_load writes it; 10 minutes)."""
    import pathlib
    summary = pathlib.Path(__file__).resolve().parent.parent / "docs" / "load" / "load.md"
    if not summary.exists():
        return ["## Load", "", "Not run: `./scripts/bench_load` writes docs/load/.", ""]
    return LOAD_TEXT.strip().split("\n")[:2] + ["", summary.read_text().strip()] + LOAD_TEXT.strip().split("\n")[2:] + [""]


LOAD_TEXT = """
## Load: the node under TF at 1 kHz and detections at 30 Hz (`./scripts/bench_load`, 10 minutes)
The calibration node as `calibrate.launch` starts it, driven by `benchmark/load.cpp`.

The driver publishes the robot TF at 1 kHz and, from 1 s later, a tag detection at 30 Hz, each
stamped when it is sent. It moves the simulated robot through 60 poses per session (2 s still, 1 s
moving); at the end of each session it calls `/reset`, so the run is several long sessions, not
one ever-growing set. Once a second it reads the node's CPU time and RSS from `/proc/<pid>`, and
the node's `~status`: detections handled, and their age (now minus stamp) over the last 300. The
age table groups those seconds by the samples the session held. The load driver, roscore and the
node share the machine's 2 cores. `test/load.test` runs the same for 20 s and asserts that no
detection is lost, that the median age stays below a frame period, and that RSS does not grow.

![RSS, CPU, samples and detection age over the 10 minutes](docs/load/load.png)

The age no longer grows with the session: the detection thread only hands each observation to
the session under a short lock (and writes the session file when it completes a sample); the
estimate and the ranking of 150 next-pose candidates run on the node's worker thread at a lower
priority, on a copy of the samples. At 60 samples a ranking takes about half a second there, and
no detection waits for it. The per-second rows are in `docs/load/load.csv`.
"""


def corners_section():
    """--method corners: its speed (handeye_bench_corners) and the rendered study (handeye_corners_study)."""
    import pathlib
    speed_file = pathlib.Path(run) / "corners_speed.json"
    study_file, focal_file = pathlib.Path(run) / "corners_study.md", pathlib.Path(run) / "corners_study_focal.md"
    head = ["## Calibration from the corners (`--method corners`)", ""]
    if not speed_file.exists():
        return head + ["Not run in this pass of `./scripts/bench`.", ""]
    _, speed = medians(str(speed_file))
    goals = {0: "<= 20 ms", 2: "<= 100 ms"}
    what = {0: "X + Y + covariance, robot exact (its data too)", 1: "robot poses free (noise given)",
            2: "robot poses and intrinsics free", 3: "robot poses free, their noise estimated",
            4: "robot noise estimated, intrinsics free"}
    rows = []
    for k in range(5):
        t = speed[f"BM_CornerCalibration/{k}"] / 1e3
        goal = goals.get(k, "")
        met = ("yes" if t <= float(goal.split()[1]) else "no") if goal else ""
        rows.append(f"| `BM_CornerCalibration/{k}` | {what[k]} | {t:.1f} | {goal} | {met} |")
    return head + [
        "`handeye_bench_corners`: 30 images x 50 corners (0.3 px, robot poses off by 0.3 mm / 0.03 deg per axis;",
        "for /0 at the true robot poses, as that model assumes), started 1 mm / 0.1 deg off; Ceres 2.1, one",
        "thread, median of 5 repetitions.",
        "",
        "| benchmark | free | time [ms] | goal | met |",
        "|---|---|---:|---|:---:|",
    ] + rows + [
        "",
        "Rendered sessions with known truth (`handeye_corners_study --sessions 300`, and with",
        "`--focal-error 0.01`): 30 eye-in-hand views at 0.4-1.0 m of each target, rendered with blur, noise",
        "(2 gray levels) and lens distortion, each sensor pixel the average of 5 x 5 samples (at 3, the",
        "tests' default, the renderer's own corner errors show), detected and calibrated as `handeye images`",
        "does; corners against the pose level (`--method joint`) on the same images. The bound is the corner",
        "model's Cramer-Rao bound: the inverse information of the detected corners at the truth, each image",
        "at the pixel sigma the corner fit weighed it with. No estimator's RMS error is under it, so poses /",
        "bound is the least corners / poses can be. The last column: the share of sessions whose images",
        "failed the test of one pixel sigma and were each weighed by their own. The corner fit carries the",
        "target's geometry error it estimates from the corners (docs/how_it_works.md: the corner estimator). Goals:",
        "corners / poses <= 0.85x, corners / bound <= 1.05x, NEES of X in [5.5, 6.5].",
        "",
        study_file.read_text().strip() if study_file.exists() else "(not run)",
        "",
        "The focal length given 1% long (the images rendered with the true one); corners with",
        "`--refine-intrinsics` (goals: the refined focal length within 2 sigma, X's mean error under 0.2",
        "sigma, where the pose level is biased):",
        "",
        focal_file.read_text().strip() if focal_file.exists() else "(not run)",
        "",
    ]


run = sys.argv[1]
context, default = medians(f"{run}/default.json")
_, no_trim = medians(f"{run}/no_trim.json")
_, compare = medians(f"{run}/compare.json")
accuracy = open(f"{run}/accuracy.md").read()
validation = open(f"{run}/validation.txt").read()
systematic = open(f"{run}/systematic.txt").read()
next_best_pose = open(f"{run}/next_best_pose.md").read()
_, detectors = medians(f"{run}/detectors.json")
_, motion = medians(f"{run}/motion.json")
auto_study = open(f"{run}/auto_study.md").read()
auto_study_estimated = open(f"{run}/auto_study_estimated.md").read()
controller_study = open(f"{run}/controller_study.md").read()
stops = open(f"{run}/stops.txt").read()
arm_images = open(f"{run}/arm_images.txt").read()
check_study = open(f"{run}/check_study.md").read()
check_study_rendered = open(f"{run}/check_study_rendered.md").read()
check_study_rendered_60 = open(f"{run}/check_study_rendered_60.md").read()
check_frontier = open(f"{run}/check_frontier.md").read()
check_estimated_scale = open(f"{run}/check_estimated_scale.md").read()
check_between = open(f"{run}/check_between.md").read()
check_any_direction = open(f"{run}/check_any_direction.md").read()
commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()


def row(name):
    return f"| `{name}` | {default[name]:,.1f} | {no_trim[name]:,.1f} |"


def ratio(table, family, big, small):
    return table[f"{family}/{big}"] / table[f"{family}/{small}"]


lines = [
    "# Benchmarks",
    "",
    "Regenerate everything on this page with `./scripts/bench` (it rewrites this file); the Load section\nreads `docs/load/`, which `./scripts/bench_load` writes (10 minutes, run it separately).",
    "",
    f"Machine: {cpu_model()}, {context.get('num_cpus')} cores at {context.get('mhz_per_cpu')} MHz, "
    f"Debian bookworm, g++ -O3 (CMake Release), Eigen 3.4, commit `{commit}`. "
    "Google Benchmark, every size in one process, median of 5 repetitions, wall time.",
    "",
    "## Solve plus covariance (`handeye_benchmark`)",
    "",
    "`BM_SolveMotions/k`: k independent pairs, the paper's protocol at lambda = 1e-4 (noise given).",
    "`BM_SolveSamples/k`: a pose stream of k+1 samples (k motions) with the correlated covariance.",
    "`BM_SolveSamplesEstimatedNoise/30`: no noise block; the noise is estimated from the residuals.",
    "",
    "| benchmark | default allocator [us] | heap trimming off [us] |",
    "|---|---:|---:|",
]
suggest = {n: v for n, v in default.items() if n.startswith("BM_SuggestNextPose")}
for name in sorted((n for n in default if n not in suggest), key=lambda n: (n.split("/")[0], int(n.split("/")[1]))):
    lines.append(row(name))
lines += [
    "",
    "| goal | default allocator | heap trimming off |",
    "|---|---:|---:|",
    f"| k = 30 pairs in <= 50 us | {default['BM_SolveMotions/30']:.1f} us | {no_trim['BM_SolveMotions/30']:.1f} us |",
    f"| pairs: time(10 000) / time(1 000) in 8-12 | {ratio(default, 'BM_SolveMotions', 10000, 1000):.1f} | {ratio(no_trim, 'BM_SolveMotions', 10000, 1000):.1f} |",
    f"| pose stream: time(10 000) / time(1 000) in 8-12 | {ratio(default, 'BM_SolveSamples', 10000, 1000):.1f} | {ratio(no_trim, 'BM_SolveSamples', 10000, 1000):.1f} |",
    "",
    "The reference Python implementation takes about 25 ms at k = 30.",
    "",
    "### The joint estimator (X and the pattern pose from the absolute poses)",
    "",
    "`BM_SolveJoint/k`: k+1 poses, noise given (the paper's noise at lambda = 1e-5, robot noise included, so",
    "the weights follow the estimate); `BM_SolveJointEstimatedNoise/30`: no noise block, the camera and",
    "robot noise estimated (REML) with the solve; `BM_SolveJointSessions/0|1`: 32 seeded 31-pose sessions",
    "per iteration, noise given (0) or estimated (1); `BM_SuggestNextPoseJoint/n`: 150 candidates ranked for a",
    "session of n samples, each by a rank-6 update of the 12x12 information.",
    "",
    "| goal | default allocator | heap trimming off | met |",
    "|---|---:|---:|:---:|",
]
def goal(label, d, t, ok):
    return f"| {label} | {d} | {t} | {'yes' if ok else 'no'} |"
joint_ratio = (ratio(default, 'BM_SolveJoint', 10000, 1000), ratio(no_trim, 'BM_SolveJoint', 10000, 1000))
estimated = (default['BM_SolveJointEstimatedNoise/30'] / default['BM_SolveJoint/30'],
             no_trim['BM_SolveJointEstimatedNoise/30'] / no_trim['BM_SolveJoint/30'])
# Over 32 seeded sessions (the fit takes one round or two, by session): the figure the goal is judged by.
sessions = (default['BM_SolveJointSessions/1'] / default['BM_SolveJointSessions/0'],
            no_trim['BM_SolveJointSessions/1'] / no_trim['BM_SolveJointSessions/0'])
lines += [
    goal("31 poses, solve + covariance <= 60 us", f"{default['BM_SolveJoint/30']:.1f} us", f"{no_trim['BM_SolveJoint/30']:.1f} us",
         min(default['BM_SolveJoint/30'], no_trim['BM_SolveJoint/30']) <= 60),
    goal("1 000 poses <= 3 ms", f"{default['BM_SolveJoint/1000'] / 1e3:.2f} ms", f"{no_trim['BM_SolveJoint/1000'] / 1e3:.2f} ms",
         min(default['BM_SolveJoint/1000'], no_trim['BM_SolveJoint/1000']) <= 3000),
    goal("10 000 poses <= 30 ms", f"{default['BM_SolveJoint/10000'] / 1e3:.1f} ms", f"{no_trim['BM_SolveJoint/10000'] / 1e3:.1f} ms",
         min(default['BM_SolveJoint/10000'], no_trim['BM_SolveJoint/10000']) <= 30000),
    goal("time(10 000) / time(1 000) in 8-12", f"{joint_ratio[0]:.1f}", f"{joint_ratio[1]:.1f}", any(8 <= r <= 12 for r in joint_ratio)),
    goal("estimated noise <= 3x given noise (31 poses, mean over 32 sessions)",
         f"{sessions[0]:.2f}x ({default['BM_SolveJointSessions/1'] / 32:.0f} us)",
         f"{sessions[1]:.2f}x ({no_trim['BM_SolveJointSessions/1'] / 32:.0f} us)", max(sessions) <= 3),
    goal("(the benchmark's one session, one round: estimated / given)", f"{estimated[0]:.2f}x", f"{estimated[1]:.2f}x",
         max(estimated) <= 3),
    goal("ranking 150 candidates at 30 samples <= 5 ms", f"{default['BM_SuggestNextPoseJoint/30'] / 1e3:.2f} ms",
         f"{no_trim['BM_SuggestNextPoseJoint/30'] / 1e3:.2f} ms", default['BM_SuggestNextPoseJoint/30'] <= 5000),
    goal("ranking 150 candidates at 300 samples <= 20 ms", f"{default['BM_SuggestNextPoseJoint/300'] / 1e3:.2f} ms",
         f"{no_trim['BM_SuggestNextPoseJoint/300'] / 1e3:.2f} ms", default['BM_SuggestNextPoseJoint/300'] <= 20000),
]
lines += [
    "",
    "Where the time goes at 31 poses (perf): two linearisations of the 31 samples (the residual's log,",
    "the whitened Jacobian and the 12x12 information; the first also each sample's 6x6 Cholesky",
    "inverse, which the second keeps: a step under 0.1 sigma is taken without a confirming",
    "linearisation), the O(n) start with its degeneracy checks, and the leverages of the kurtosis",
    "test. The estimated-noise mode starts its noise from a least-squares fit of the start's residual",
    "outer products (MINQUE(0)) on the start's linearisation, which its first Gauss-Newton step reuses",
    "(residuals linearly predicted), runs two AI-REML steps (two evaluations, A M A per sample each, the",
    "first on the solve's own Cholesky factors; the second step unconfirmed) on every sample's REML",
    "scatter, takes one more",
    "predicted step under the fitted noise and makes one more pass for the noise's own uncertainty",
    "(X's inflation and Y's, each through its own whitened columns) and for the check that a REML",
    "step from the fit on the new residuals is under 0.1",
    "sigma of each number, or moves X by under 0.1 sigma and Sigma_X by under 0.1 of its own spread.",
    "About 3.5% of sessions fail it and take a second round. Callgrind over the 32 sessions of",
    "BM_SolveJointSessions at `ac0f077`: 1.43M instructions per solve estimated against 0.49M given, 2.94x.",
    "Smaller per-sample terms (216 bytes instead of 568: no stored dV/dE, no Isometry fourth rows) took",
    "0.05M off the estimated solve and 0.03M off the given one, so the ratio rose from 2.84x while both",
    "times fell; six wall-time runs (three per column) read 2.75-2.84x. (Y's own inflation added 0.12M;",
    "the fit's small inverses from the LDLT factors, the traces without forming N_i, the first",
    "evaluation on the solve's own whitening, one 12x12 inverse per linearisation instead of three, and",
    "the summary's numbers by to_chars took it back.)",
    "",
    "### Why two columns",
    "",
    "On this sandbox a page fault costs 2-10 us (measured by touching fresh mmapped pages, and by the",
    "solver below; bare-metal Linux takes 0.1-0.25 us). A solve at k = 1 000 allocates about 2 MB of per-motion",
    "state; glibc returns it to the kernel when the solve ends (heap trimming) and faults it back in",
    "at the next solve, about 230 faults per solve, which is about 2.5 ms here. `handeye_benchmark` reports",
    "the faults per iteration of the joint benchmarks (`faults`; one solve, 32 in the sessions one): the solve at 1 000 poses faulted 343",
    "pages back in per solve (2.17 ms against 1.43 ms without) until its terms were made smaller; now",
    "none of the joint benchmarks faults in either column. The \"heap trimming off\" column",
    "(`MALLOC_TRIM_THRESHOLD_`, `MALLOC_MMAP_THRESHOLD_` raised) measures the solver itself; the",
    "first column is what a caller gets with glibc's defaults on this machine. The library does not",
    "change allocator settings behind the caller's back. A caller that solves many large problems",
    "in a loop (Monte-Carlo studies) can export the two variables itself.",
    "",
]
methods = ["Tsai", "Park", "Horaud", "Andreff", "Daniilidis"]
lines += [
    "## Ours against OpenCV's `cv::calibrateHandEye` (`handeye_compare`)",
    "",
    "Identical pose data, eye-in-hand, n absolute poses:",
    "- camera noise depth-heavy: sigma 0.3/0.3/1.5 mm and 0.15/0.15/0.05 deg;",
    "- robot noise 0.05 mm and 0.01 deg.",
    "",
    "OpenCV builds all n(n-1)/2 motion pairs. Ours pairs each pose with the next 30: all pairs up to",
    "n = 31, about 30 n pairs beyond. It weights each pair by its covariance, and returns the covariance",
    "as well. Median wall time in us, one process, heap trimming off, after one",
    "warm-up solve (see \"Why two columns\"):",
    "",
    "| n | ours (solve + covariance) | " + " | ".join(methods) + " |",
    "|---:|---:|" + "---:|" * len(methods),
]
for n in (10, 30, 100, 300):
    cells = [f"{compare[f'BM_OpenCV/{i}/{n}']:,.1f}" for i in range(len(methods))]
    lines.append(f"| {n} | {compare[f'BM_Ours/{n}']:,.1f} | " + " | ".join(cells) + " |")
lines += [
    "",
    "Ours on k independent motion pairs: " + ", ".join(f"k = {k:,}: {compare[f'BM_OursMotions/{k}']:,.0f} us" for k in (30, 100, 1000, 10000, 100000))
    + f" (100 000 / 10 000 = {compare['BM_OursMotions/100000'] / compare['BM_OursMotions/10000']:.1f}).",
    f"A Monte-Carlo run of 1 000 datasets (what the analytic covariance replaces) takes "
    f"{compare['BM_MonteCarlo1000'] / 1e3:,.0f} ms." if 'BM_MonteCarlo1000' in compare else "",
    "",
    "### Accuracy on the same data (n = 30 poses, M = 300 datasets)",
    "",
    accuracy.strip(),
    "",
    "**Targets.** The joint estimator: RMS rotation error <= 0.85x and translation <= 0.80x",
    "the best OpenCV method's, and within 1.05x of the Cramer-Rao bound computed from the true noise (the",
    "inverse Fisher information at the truth, on the same views). The ratios are printed above. The",
    "pairs estimator weights each pair by its marginal covariance; their correlation through the shared",
    "poses is in its covariance but not in its weights, so it stays near 0.9x.",
    "",
    "## Detectors per image (`handeye_bench_detectors`)",
    "",
    "What `target_detector` and `handeye images` do per image: rectify, detect, PnP with the covariance,",
    "on a rendered view of each target at 0.5-0.6 m (blur, noise, lens distortion), median of 5 runs, one",
    "process. The goal is 30 ms per image on this machine at both sizes; the last column is the",
    "ratio to the chessboard at 640 x 480. Targets: a 9 x 6 chessboard, a 6 x 5 ChArUco board, one ArUco",
    "marker, a 2 x 2 AprilTag board. libapriltag's quad search runs on the image shrunk by width / 640",
    "(`quad_decimate` 0, the default: 2 at 1280 x 720, 32 ms at full size before; the corners are",
    "still fitted on the full image and their covariance stays honest, `test_vision`).",
    "",
    "| target | 640 x 480 [ms] | 1280 x 720 [ms] | 1280 x 720 / chessboard 640 |",
    "|---|---:|---:|---:|",
] + [f"| {kind} | {detectors[f'BM_DetectAndEstimate/{kind}/640'] / 1e3:.1f} | {detectors[f'BM_DetectAndEstimate/{kind}/1280'] / 1e3:.1f} | "
     f"{detectors[f'BM_DetectAndEstimate/{kind}/1280'] / detectors['BM_DetectAndEstimate/chessboard/640']:.1f}x |"
     for kind in ("chessboard", "charuco", "aruco", "apriltag")] + [
    "",
] + corners_section() + [
    "## Next-best pose: samples to a target sigma (`handeye_next_best_pose --seeds 30 --target-mm 0.3 --candidates 100`)",
    "",
    "Simulated sessions with known truth. Each starts from the same 3 random poses and adds one pose",
    "at a time until the predicted object 1 sigma at 0.7 m (the node's `object_error_mm`) reaches the",
    "target: a random reachable view of the pattern, or the best of 100 such views ranked by the",
    "predicted covariance (`/suggest_pose`, `handeye suggest`). The last column is the mean 6-dof",
    "NEES of the final X against the truth (expected 6): stopping on a predicted sigma does not make",
    "the covariance dishonest.",
    "",
    next_best_pose.strip(),
    "",
    "Time for one suggestion (150 sampled candidates ranked; n samples so far): `BM_SuggestNextPose/n` ranks",
    "with the pairs estimator (a re-solve per candidate), `BM_SuggestNextPoseJoint/n` with the joint one",
    "(a rank-6 update of the information per candidate):",
    "",
    "| benchmark | default allocator [ms] | heap trimming off [ms] |",
    "|---|---:|---:|",
] + [f"| `{name}` | {default[name] / 1e3:,.2f} | {no_trim[name] / 1e3:,.2f} |" for name in sorted(suggest, key=lambda n: (n.split('/')[0], int(n.split('/')[1])))] + [
    "",
    "## The view planner: one step of the robot moving itself (`handeye_bench_motion`)",
    "",
    "The simulated arm (`urdf/sim_arm.urdf`, UR5 kinematics, a camera on the flange, the table plane), after",
    "6 samples: the session ranks 150 candidate views (next-best pose), then the planner checks them best",
    "first (`motion/view_planner.h`: workspace, target in view, inverse kinematics from the current joints",
    "and 6 random starts, joint limits, joint step, collision at the goal and along the path). Up to the first",
    "view that passes is what a move costs; all 150 is the goal's bound (<= 200 ms on one core).",
    "",
    "| step | median [ms] |",
    "|---|---:|",
    f"| ranking 150 candidates (`BM_RankCandidates`) | {motion['BM_RankCandidates'] / 1e3:.2f} |",
    f"| planning up to the first view that passes (`BM_PlanView/check_all:0`) | {motion['BM_PlanView/check_all:0'] / 1e3:.1f} |",
    f"| a verdict on all 150 (`BM_PlanView/check_all:1`) | {motion['BM_PlanView/check_all:1'] / 1e3:.0f} |",
    "",
    "## The robot moving itself against easy_handeye's star (`handeye_auto_study --seeds 20 --target-mm 1.0`)",
    "",
    "The simulated arm from 20 seeded start views (the board whole in a 60 x 45 deg image), the rig simulator's",
    "detection noise (0.3 mm, 0.05 deg) and a small robot noise (0.05 mm, 0.005 deg). `auto`",
    "(auto/auto_calibration.h): two 5 cm shifts and two 20 deg turns about the target to start, then the",
    "session's ranking through the planner, until the object 1 sigma at 0.7 m is 1 mm. The star: easy_handeye's",
    "17 poses around the start (+-25 and +-12.5 deg about the effector's axes, +-5 cm x, +-10 cm y, +3.3 cm z),",
    "each checked by the same planner, through the same session. A sample is taken where the board is whole in",
    "the image. The goal: auto needs at most 0.6x the star's samples to reach the same sigma.",
    "Through ROS (the node, the simulated controller and camera: `rostest handeye_covariance arm_calibrates.test`),",
    "the noise is estimated from the residuals (below), and the same start reaches 1 mm in 7 samples at about",
    "4.9 s per view (planning, moving at 10% of the URDF's speed, settling, sampling); the test prints both.",
    "",
    auto_study.strip(),
    "",
    "### With the node's noise: estimated from the residuals (`handeye_auto_study --seeds 10000 --target-mm 1.0 --noise estimated`)",
    "",
    "The node's own configuration in simulated_arm.launch: the rig's detections carry no covariance and the",
    "robot pose comes from TF, exact, so the session estimates the noise from the residuals. X's NEES against",
    "the truth where auto stopped, by the sample count it stopped at. An estimated noise reaches a target only",
    "from 7 samples (`target_progress`, estimation/next_best_pose.h): before that rule (one run of 1000 seeds with it set to 3), the sessions that",
    "stopped at 5 samples (110 of 1000) had a mean NEES of 11.0 and those at 6 of 7.0, the ones whose noise came",
    "out small by chance. The NEES of an estimated noise has an F-like tail, heavier than chi2(6)'s; the",
    "rostest's single draw is held to this reference's 99.9% point.",
    "",
    auto_study_estimated.strip(),
    "",
    "### Rendered images (`simulated_arm.launch images:=true`; `test_arm_images`, a gtest)",
    "",
    "The node's image path without ROS: the launch's camera, 9 x 6 x 20 mm chessboard, board pose, renderer and",
    "target_detector settings, the detections' covariance under the pixel sigma pooled from their residuals, the robot",
    "exact; auto until 1 mm at 0.7 m. From the launch's own start every view is pixel-aligned and the runs differ only in",
    "pixel noise (one geometry's corner errors); from random starts each seed is another geometry",
    "(docs/how_it_works.md, \"Rendered images on the simulated arm\"; the HANDEYE_ARM_* knobs regenerate each row).",
    "",
    "Before the renderer's texture levels (772c62e, the old 0.05 px detector floor), from the launch's start with the",
    "board along the pixel rows, the detections' NEES read 25.7 and X's 41.9 over 20 seeds. Now, each start and board",
    "pose (the knobs on each line's head; the first is the test's own, whose figures it asserts):",
    "",
    "```",
    arm_images.strip(),
    "```",
    "",
    "## Stopping the arm",
    "",
    "The robot moving itself against a controller that follows joint_trajectory_controller's rules",
    "(simulation/trajectory_controller.h), speed scaling as the UR driver's scaled controller runs it, and every stop",
    "path (docs/motion.md). First without ROS (`handeye_auto_study --seeds 20 --controller on`): the auto calibrations",
    "of the table above with each move made through the controller and the move monitor, the speed scale constant or",
    "changed once half the move's path is covered; then a protective stop at a fraction of a random move (40 moves a",
    "row, speed fraction 0.1 and 0.2): the time from the arm's stop to the node's; then a controller that refuses",
    "every command.",
    "",
    controller_study.strip(),
    "",
    "Through the node (`rostest handeye_covariance arm_calibrates.test case:=<path>`, one run each, moves at speed",
    "fraction 0.2 but for speed_scale): the joint travel after each stop, from the arm's own joint states, and the",
    "speed of its fastest joint when the stop came (a stall, a refused or a scaled move stops a slow arm). The tests",
    "hold the travel to 0.5 deg.",
    "",
    "```",
    stops.strip(),
    "```",
    "",
    "## Checking a saved calibration (`handeye_check_study --checks 300`, `test_real_data`)",
    "",
    "`handeye check` (estimation/calibration_check.h) on simulated sessions: a calibration from 20 views, 5 new",
    "views per check (300 checks per row, so a rate's 1 sigma is about 1.7 points at 90%), X's or Y's translation",
    "moved along a random direction by the given multiple of the check's own 1 sigma of the change along it",
    "(1 / sqrt(u' Cov^-1 u): the noncentrality is the multiple squared). Beside it: the bound for a 6-dof test",
    "that knows which of X and Y would move (noncentral chi2(6)), and the bound for any test that must catch",
    "either at the same alpha (the Neyman-Pearson test against their even mixture at each check's views, a",
    "direction uniform in 6 dof: no test's power against both exceeds it); how often the check detects and names",
    "right beside the most any test with any naming can at each check's views (two_hypothesis_frontier: the check's",
    "own test, the larger chi2 drop named by the larger). alpha = 1%. Noise stated unless said.",
    "",
    check_study.strip(),
    "",
    "Through the images (`handeye_check_study --rendered config/tag_board_2x2.yaml --checks 600`,",
    "simulation/rendered_views.h): each calibration's 20 views and each check's 5 rendered and detected as",
    "`handeye images` and `handeye check --images` detect them (the pixel sigma pooled over the set, the",
    "robot's noise estimated beside the detections' covariance). Beside them: the 6-dof bound when the views'",
    "noise is known only up to one scale, from as many dof as the calibration's own views give its leave-one-out",
    "prediction (at most 6 a view: f_test_power, the F test, the most powerful test invariant to that scale and to",
    "the change's direction), and the new",
    "views' chi2 / dof:",
    "",
    check_study_rendered.strip().split("\n", 2)[2],
    "",
    "The same from 60-view calibrations (`--calibration-views 60 --checks 150`): the noise known to three",
    "times the dof, the check's null narrower:",
    "",
    check_study_rendered_60.strip().split("\n", 2)[2],
    "",
    "Where detecting and naming meet (`handeye_check_study --frontier`, two_hypothesis_frontier): how much",
    "X's and Y's subspaces overlap at the views sets both the most any test detects (the bound) and the most any",
    "test with any naming detects and names right (the check's own test). The goal of 90% detected with 95% of",
    "them named right needs the first >= 90% and the second >= 85.5%.",
    "",
    check_frontier.strip(),
    "",
    "What an estimated noise costs (`handeye_check_study --estimated-scale`): the bound for a test that must catch",
    "X or Y when the views' noise is known only up to one scale, estimated from 360, 120 or 60 dof (the",
    "leave-one-out prediction of 60, 20 or 10 views), the most powerful test invariant to that scale",
    "(two_hypothesis_power_bound_estimated_scale; by Hunt and Stein no test's smallest power over the scale exceeds",
    "it); the last row a test that knows which (the F test, f_test_power).",
    "",
    check_estimated_scale.strip(),
    "",
    "At views between the usual and the turned ones (`handeye_check_study --views-between --checks 2000`;",
    "mean cosine 0.73, unequal):",
    "",
    check_between.strip().split("\n", 2)[2],
    "",
    "Any direction (`handeye_check_study --any-direction --checks 2000`): at the usual views, X or Y moved along a",
    "direction uniform in its 6 dof as the check weighs them (u = L w, L L^T the check's covariance of the change,",
    "the family the bound for X or Y is for) beside its translation; then the translation moved by 5 times the",
    "1 sigma the check prints beside a change (the translation's own spread along the move, the goal's words read",
    "literally), which exceeds the bounds' 1 sigma where the change's rotation and translation correlate:",
    "",
    check_any_direction.strip().split("\n", 2)[2],
    "",
    "Real sessions (`test_real_data`, `ChecksOfACalibrationOnEverySession`): 200 random splits of each into a",
    "calibration and 5 check views (the 8-view Franka sessions: each of their 28 splits into 6 and 2 once), the",
    "calibration as a user gets it (the KUKA ones, which use the shared robot error, predicted under it, each part",
    "taking the whole session's model numbers as it takes its inflation); false",
    "alarms without a change, and a 2 mm move of the camera on its mount detected, in the splits whose 5 sigma",
    "allows it; under a short session's line with an alarm, its count against a parametric-bootstrap reference (100",
    "sessions simulated at its robot poses with its fitted noise, the same splits checked alike); the eye-in-hand",
    "Franka session's images, which hold a change, also views 7 and 8 against a calibration of views 1-6 and the",
    "false alarms of views 1-6 alone (their 15 splits into 4 and 2, against their own reference):",
    "",
    "```",
    *[line for line in systematic.splitlines() if line.startswith(("[check, real", "  reference (", "  reference with", "  views ", "  each of views", "  rotation residuals"))],
    "```",
    "",
    "## Honesty under systematic errors and on real data",
    "",
    "`test_systematic` (simulation/systematic.h): 200 sessions of 30 poses per case, the NEES of X for the",
    "plain covariance (the Gaussian model with the stated detector noise taken as true) and for the default",
    "path (outlier stage, the missing noise estimated when the stated noise fails chi2, Huber and the sandwich",
    "when the residuals are heavy-tailed). Each is judged against its own pseudo-true X, the limit of the same",
    "procedure on 2 000 poses of the same robot (the true X for heavy tails); 20 robots for the kinematic case.",
    "Then the split-half check on 60-pose sessions with robust mode on. `test_honesty`: the calibrated check's",
    "reference on simulated honest sessions of 8, 16 and 30 samples (the session's split-half NEES over its",
    "parametric-bootstrap reference at the same poses), and a noise stated 3x too small caught and inflated.",
    "`test_view_noise`: views at 0.3-1.5 m with a board's distance-dependent noise, poses without a covariance:",
    "the view-following model against the homogeneous one. `test_symmetric`: symmetric boards, each view's",
    "candidate decided from the motion, on the real sessions with turns planted and on rendered sessions.",
    "`test_real_data`: every real session of `../shared/realdata` on both paths (the images with the detector's",
    "covariances; their poses without a covariance), judged against its own reference; the Franka sessions",
    "against ViSP's published X, the KUKA sessions against X_park (OpenCV's PARK on the same detections), with",
    "the combined uncertainty (ours and the jackknife spread of our pipeline for theirs).",
    "",
    "```",
    systematic.strip(),
    "```",
    "",
    "## Monte-Carlo validation (`handeye validate --protocol all --M 10000`)",
    "",
    "epsilon is eq. (63), with its sampling floor in brackets. NEES is expected to be 3 (R, t) and",
    "6 (6 dof). Coverage is the share inside the predicted 95% ellipsoid. The last two columns are",
    "eq. (35)/(56) as printed. The time column covers solve and covariance. The joint-* protocols run",
    "the joint estimator on pose streams of k+1 poses and give the NEES of X and of Y, with the pairs",
    "estimator's X on the same data beside it; with the noise estimated, the NEES of X and of Y is",
    "bounded by Hotelling's F mean 6 nu / (nu - 2) = 6.43 for nu = 29 (one variance per axis from the",
    "residuals); each has its own inflation for the noise estimate's error (one for both left Y at 6.50).",
    "",
    "```",
    validation.strip(),
    "```",
    "",
    "Plots (the paper's Fig. 2 and Fig. 3):",
    "- `docs/validation/fig3_epsilon.png`: epsilon against lambda, with the floor;",
    "- `docs/validation/fig2_<protocol>.png`: 1-sigma ellipses, predicted against Monte-Carlo.",
    "",
    "![epsilon vs lambda](docs/validation/fig3_epsilon.png)",
    "",
    "![paper protocol, 1-sigma ellipses](docs/validation/fig2_paper.png)",
    "",
] + load_section()
print("\n".join(lines))
