#!/usr/bin/env python3
"""Writes docs/results.md (to stdout) from the outputs of scripts/reproduce.sh.

    python3 scripts/results_doc.py WORK_DIR ELAPSED_SECONDS > docs/results.md

Reads WORK_DIR/runs/<source>_<mode>[_improved|_vote]/report.json (bodyseg-eval reports, one
configuration per row; for BlazePose also the per-recording reports under them),
WORK_DIR/projection.md and WORK_DIR/subset/report.json. Every number
in the document comes from those files; the reading of them is computed here too, so that a
rerun on other code says what that code does.
"""

import json
import re
import sys
from pathlib import Path

CLASSES = ["head", "torso", "upper_arms", "lower_arms", "upper_legs", "lower_legs", "background"]
TITLES = ["Head", "Torso", "Upper arms", "Lower arms", "Upper legs", "Lower legs", "Background"]
BODY = CLASSES[:6]
PAPER = ["Reference", "M", "N", "M-N", "M-R-N"]
# The paper's synthetic-data result (its Table 1): M-R-N change from Reference.
PAPER_GAIN = {"biou": 1.32, "lower_arms": 4.68}


def load(path: Path):
    """{configuration: {"iou": {class: %}, "miou", "biou", "ap", "f1"}} of a report."""
    report = json.loads(path.read_text())
    out = {}
    for c in report["configurations"]:
        m = c["metrics"]
        iou = {pc["class"]: 100.0 * pc["iou"] for pc in m["per_class"] if pc["iou"] is not None}
        out[c["name"]] = {
            "confusion": c["confusion"]["counts"],  # [truth][prediction], report["classes"] order
            "classes": report["classes"],
            "iou": iou,
            "miou": 100.0 * m["miou"],
            "biou": 100.0 * m["biou"],
            "ap": 100.0 * m["ap"],
            "f1": 100.0 * m["f1"],
        }
    return out


def table(rows, reference="Reference"):
    """The paper's layout: per-class IoU, mIoU, BIoU, AP, F1; a change row under each."""
    head = "| Configuration | " + " | ".join(TITLES) + " | mIoU | BIoU | AP | F1 |"
    lines = [head, "|---" + "|---:" * (len(TITLES) + 4) + "|"]
    ref = rows[reference]

    def values(r):
        return [r["iou"].get(c, float("nan")) for c in CLASSES] + [r["miou"], r["biou"], r["ap"], r["f1"]]

    for name, r in rows.items():
        lines.append(f"| {name} | " + " | ".join(f"{v:.2f}" for v in values(r)) + " |")
        if name != reference:
            d = [a - b for a, b in zip(values(r), values(ref))]
            lines.append("| Δ vs Reference | " + " | ".join(f"{v:+.2f}" for v in d) + " |")
    return "\n".join(lines)


def gains(rows, name="M-R-N"):
    ref, r = rows["Reference"], rows[name]
    per_class = {c: r["iou"][c] - ref["iou"][c] for c in BODY}
    return r["biou"] - ref["biou"], per_class


def by_preset(run_dir: Path, name):
    """{preset: confusion matrix} of configuration `name`, the matrices of a run's recordings
    (`<preset>_<seed>/report.json`) summed per preset, and the report's class order."""
    sums, classes = {}, CLASSES
    for path in sorted(run_dir.glob("*/report.json")):
        preset = path.parent.name.rsplit("_", 1)[0]
        rows = load(path)[name]
        m = sums.setdefault(preset, [[0] * len(r) for r in rows["confusion"]])
        for i, r in enumerate(rows["confusion"]):
            m[i] = [a + b for a, b in zip(m[i], r)]
        classes = rows["classes"]
    return sums, classes


def body_iou_by_preset(run_dir: Path, name="M-R-N"):
    """{preset: BIoU %} of configuration `name` (see `by_preset`)."""
    sums, classes = by_preset(run_dir, name)

    def biou(m):
        ious = []
        for c in BODY:
            k = classes.index(c)
            tp = m[k][k]
            union = sum(m[k]) + sum(r[k] for r in m) - tp
            if union:
                ious.append(100.0 * tp / union)
        return sum(ious) / len(ious)

    return {preset: biou(m) for preset, m in sums.items()}


def body_errors_by_preset(run_dir: Path, name="Reference"):
    """{preset: (% of the true body points predicted background or unknown, % predicted as
    another body part)} of configuration `name` (see `by_preset`)."""
    sums, classes = by_preset(run_dir, name)
    body = [classes.index(c) for c in BODY]
    bg = classes.index("background")
    out = {}
    for preset, m in sums.items():
        total = sum(sum(m[t]) for t in body)
        missed = sum(m[t][bg] for t in body)
        wrong_part = sum(m[t][p] for t in body for p in body if p != t)
        out[preset] = (100.0 * missed / total, 100.0 * wrong_part / total)
    return out


def against_paper(runs, source, mode, setting):
    """One 2D source and projection in the paper mode and in `setting` (`improved`, `vote`):
    (paper rows, setting rows, paper M-R-N BIoU gain, setting's, setting's per-class gains,
    setting's gain / paper's)."""
    base = runs[(source, mode)]
    rows = runs[(source, f"{mode}_{setting}")]
    d0, _ = gains(base)
    d1, per_class = gains(rows)
    return base, rows, d0, d1, per_class, d1 / d0 if d0 else float("nan")


def why_not_lower_arms(rows, best):
    """Where the paper setting's gains come from, from the confusion matrices: why `best`
    and not lower arms gains most."""
    ref, mrn = rows["Reference"], rows["M-R-N"]
    k = ref["classes"].index
    bg = k("background")

    def fp_from_bg(r, c):
        return r["confusion"][bg][k(c)]

    def tp(r, c):
        return r["confusion"][k(c)][k(c)]

    support = lambda c: sum(ref["confusion"][k(c)])
    b0, b1 = fp_from_bg(ref, best), fp_from_bg(mrn, best)
    a0, a1 = fp_from_bg(ref, "lower_arms"), fp_from_bg(mrn, "lower_arms")
    lost = tp(ref, "lower_arms") - tp(mrn, "lower_arms")
    name = best.replace("_", " ")

    def num(n):
        return f"{n:,}".replace(",", " ")

    # Where the true lower-arm points went: the predicted classes whose share grew (≥ 1000).
    la = k("lower_arms")
    grown = sorted(
        ((mrn["confusion"][la][c] - ref["confusion"][la][c], ref["classes"][c])
         for c in range(len(ref["classes"])) if c != la),
        reverse=True)
    moved = ", ".join(f"{num(n)} more to {c.replace('_', ' ')}" for n, c in grown if n >= 1000)

    return (f"- **Why {name} and not lower arms gain most here** (confusion matrices, Reference → "
            f"M-R-N): in Reference {num(b0)} background points carry the {name} label "
            f"({100 * b0 / support(best):.0f}% of the true {name} points: the part's 2D label grown onto "
            f"the surfaces around it), and M-R-N gives {num(b0 - b1)} of them back to background. Lower "
            f"arms have fewer such points ({num(a0)}, of which {num(a0 - a1)} are repaired), and the "
            f"refinement also "
            + (f"takes {num(lost)} true lower-arm points away ({moved}), which the paper's Table 1 "
               f"does not show."
               if lost > 0 else f"adds {num(-lost)} true lower-arm points."))


def blazepose_section(w, work, runs):
    """The default parser against the synthetic-trained model on the benchmark, and which to
    choose when."""
    w("## BlazePose + BodyPix, the default parser, on the synthetic benchmark")
    w("")
    w("The same 300 frames with the default parser (BlazePose full on the people found from depth, body "
      "parts from BodyPix: the parser `bodyseg run` uses on real images) and with the "
      "bundled synthetic-trained model; Reference and M-R-N of each refinement setting, in %:")
    w("")
    w("| 2D labels | projection | Reference mIoU | M-R-N mIoU | Reference BIoU | M-R-N BIoU | "
      "improved M-R-N BIoU | improved + vote M-R-N BIoU |")
    w("|---|---|---:|---:|---:|---:|---:|---:|")
    for source, name in [("model", "bundled ONNX model (synthetic-trained)"), ("blazepose", "BlazePose + BodyPix")]:
        for mode in ["naive", "dsa"]:
            paper = runs[(source, mode)]
            w(f"| {name} | {mode} | {paper['Reference']['miou']:.2f} | {paper['M-R-N']['miou']:.2f} | "
              f"{paper['Reference']['biou']:.2f} | {paper['M-R-N']['biou']:.2f} | "
              f"{runs[(source, f'{mode}_improved')]['M-R-N']['biou']:.2f} | "
              f"{runs[(source, f'{mode}_vote')]['M-R-N']['biou']:.2f} |")
    w("")
    biou = {source: body_iou_by_preset(work / "runs" / f"{source}_dsa") for source in ["model", "blazepose"]}
    presets = list(biou["blazepose"])
    w("Per scene preset (DSA, paper mode, M-R-N BIoU): "
      + "; ".join(f"`{p}` BlazePose {biou['blazepose'][p]:.2f}, synthetic-trained {biou['model'][p]:.2f}"
                  for p in presets) + ".")
    w("")
    bp, model = runs[("blazepose", "dsa")], runs[("model", "dsa")]
    body = {c: bp["M-R-N"]["iou"][c] for c in BODY}
    weakest = sorted(body, key=body.get)[:2]
    d_naive, _ = gains(runs[("blazepose", "naive")])
    d_dsa, _ = gains(bp)
    d_imp, _ = gains(runs[("blazepose", "dsa_improved")])
    single = biou["blazepose"].get("single")
    crowded = [v for p, v in biou["blazepose"].items() if p != "single"]
    errors = {source: body_errors_by_preset(work / "runs" / f"{source}_naive") for source in ["model", "blazepose"]}
    w(f"- **What the numbers mean**: with DSA projection BlazePose reaches {bp['Reference']['miou']:.2f} mIoU "
      f"(Reference) and {bp['M-R-N']['miou']:.2f} after M-R-N, the synthetic-trained model "
      f"{model['Reference']['miou']:.2f} and {model['M-R-N']['miou']:.2f}; BIoU {bp['M-R-N']['biou']:.2f} against "
      f"{model['M-R-N']['biou']:.2f}. The renders are outside BlazePose's domain (it learnt from photographs; "
      f"these are mannequins of simple shapes and flat colours, the domain the bundled model was trained on), "
      f"so this is how the pipeline copes with a parser that is often wrong, not how BlazePose does on real "
      f"recordings. Its weakest classes are {weakest[0].replace('_', ' ')} ({body[weakest[0]]:.2f}) and "
      f"{weakest[1].replace('_', ' ')} ({body[weakest[1]]:.2f} IoU)"
      + (f"; it does best with one person in the room (`single`, {single:.2f} BIoU against "
         f"{max(crowded):.2f} at most with two or three people)." if single is not None and crowded
         and single > max(crowded) + 5 else "."))

    def shares(source, i):
        return ", ".join(f"`{p}` {errors[source][p][i]:.1f}%" for p in presets)

    bp_missed = {p: errors["blazepose"][p][0] for p in presets}
    w(f"- **Where it goes wrong** (Reference, naive projection: every point the colour cameras see is "
      f"labelled): of the true body points BlazePose gives another body part to {shares('blazepose', 1)} "
      f"(synthetic-trained model: {shares('model', 1)}) and background to {shares('blazepose', 0)} "
      f"({shares('model', 0)}). So the parts are wrong on a large share of the body even with one person, "
      f"BlazePose's landmarks and mask on these mannequins putting the part boundaries elsewhere"
      + ("; with two or three people it also misses more of them (further away, partly hidden), and where "
         "people overlap in a view it labels one with the other's parts (figure below)."
         if "single" in bp_missed and len(bp_missed) > 1
         and bp_missed["single"] < min(v for p, v in bp_missed.items() if p != "single") else "."))
    w(f"- **The refinement with BlazePose**: M-R-N {d_naive:+.2f} BIoU with naive projection, {d_dsa:+.2f} "
      f"with DSA, {d_imp:+.2f} with the improved refinement (DSA). "
      + ("It helps with this parser too, but it cannot make up for labels wrong over whole parts: it "
         "relabels clusters and noise from their neighbours, and a part labelled wrongly as a whole has "
         "no right neighbours." if d_dsa > 0 else "It does not help with this parser."))
    w("- **Which parser when**: on real images BlazePose (`bodyseg run`'s default; the real-photograph "
      "table below: the synthetic-trained model there is near zero), SCHP on a GPU (`--model`) for the "
      "best quality; on `bodyseg synth` recordings the synthetic-trained model "
      "(`--parser model --set parsing.segmenter=onnx`), or the recorded parser errors (`--parser recorded`) "
      "for the paper's experiment.")
    w("")


def main():
    work = Path(sys.argv[1])
    elapsed = int(sys.argv[2]) if len(sys.argv) > 2 else None
    runs = {}
    for source in ["recorded", "model", "blazepose"]:
        for mode in ["naive", "dsa"]:
            runs[(source, mode)] = load(work / "runs" / f"{source}_{mode}" / "report.json")
        for mode in ["naive", "dsa"]:
            runs[(source, f"{mode}_improved")] = load(work / "runs" / f"{source}_{mode}_improved" / "report.json")
        for mode in ["naive", "dsa"]:
            runs[(source, f"{mode}_vote")] = load(work / "runs" / f"{source}_{mode}_vote" / "report.json")
    # Improved refinement without the model's probabilities: not a summary row.
    weighted = {mode: load(work / "runs" / f"model_{mode}_weighted" / "report.json") for mode in ["naive", "dsa"]}
    subset = load(work / "subset" / "report.json")
    source_name = {"recorded": "synthetic parser errors", "model": "bundled ONNX model",
                   "blazepose": "BlazePose + BodyPix (default parser)"}
    mode_name = {
        "naive": "naive projection",
        "dsa": "DSA projection",
        "naive_improved": "naive projection, improved refinement",
        "dsa_improved": "DSA projection, improved refinement",
        "naive_vote": "naive projection, improved refinement + multi-view vote",
        "dsa_vote": "DSA projection, improved refinement + multi-view vote",
    }

    out = []
    w = out.append
    w("# Results: the paper's experiment on synthetic recordings")
    w("")
    w("Generated by `scripts/reproduce.sh` (do not edit by hand)"
      + (f" in {elapsed // 60} min {elapsed % 60} s" if elapsed is not None else "") + ".")
    w("The benchmark is [`configs/benchmarks/paper.toml`](../configs/benchmarks/paper.toml): the three scene "
      "presets (`single`, `handover`, `robot_cell`) × 4 seeds × 25 frames = 300 frames of three Kinect v2 "
      "cameras, rendered by `bodyseg synth` with the exact truth of every depth pixel. Every frame goes "
      "through `bodyseg convert` (2D labels → projection → person boxes → refinement) and is scored point "
      "by point against that truth, all frames together (ALGORITHM.md §6). IoU in %; each configuration's "
      "change from Reference under it.")
    w("")
    w("Three 2D prediction sources: the **synthetic parser errors** written with each recording "
      "(`parsing/`: small parts grown into their neighbours, boundary jitter, elbow/knee swaps, missed "
      "forearms), the **bundled ONNX model** (`models/bodyseg_parser_small.onnx`, 2D mIoU 0.63, trained "
      "on renders like these; `--parser model --set parsing.segmenter=onnx`) on the colour images, and "
      "**BlazePose + BodyPix**, the default parser for real images (BlazePose full on the people found from "
      "depth, body parts from BodyPix inside its mask; "
      "`--parser model`, `parsing.segmenter = \"blazepose\"`), on the same colour images. Two projections: "
      "**naive** (the paper's: the label of the nearest colour pixel) and "
      "**DSA** (bodyseg's: points the colour camera cannot be trusted on are left unknown, which scores as "
      "background in Reference).")
    w("")
    w("Three refinement settings: the **paper mode** (every key at its default), the **improved "
      "refinement** ([`configs/benchmarks/improved.toml`](../configs/benchmarks/improved.toml): contact "
      "graph, coverage tree, probability noise: labels the 2D parser doubted — probability below "
      "`noise_doubt_ratio` = 0.85 × the median probability of that label over the person — take no part in "
      "the clustering and N relabels them by a distance-weighted vote of about 256 sure points within "
      "`noise_doubt_radius_m` = 0.15 m, their own label weighing its probability; the synthetic "
      "parser errors carry no probabilities, so there every label counts as sure; M into the background: "
      "a body cluster lying inside a background one (a patch on a wall or on the robot) becomes background, "
      "a lower leg never (`merge_into_background`); R through noise: a "
      "cluster joined to the body tree through noise points the parser labelled body is not cut off "
      "(`remove_through_noise`); foreign colours: an arm point whose colour is rare on the person's head "
      "and torso (under 2 % of their points share its chromaticity; `foreign_color_density`) is an object "
      "held or touched — the hand-over's parcel, a robot link — and becomes background; floor contact: "
      "lower-leg points within `floor_contact_m` = 6 mm of the floor under the person become background; "
      "and smoothing: then every body point takes the body label most body points within "
      "`smooth_radius_m` = 5 cm carry, each weighing 1 / (1 + (d / 5 cm)²) — islands of another part too "
      "small for M and ragged part boundaries go to the part around them; background points neither vote "
      "nor change) "
      "and the improved refinement **+ multi-view vote** "
      "([`configs/benchmarks/improved_vote.toml`](../configs/benchmarks/improved_vote.toml), "
      "`refine.vote = \"multi_view\"`: before the steps, a point that other cameras see too — its depth "
      "agrees with theirs — takes the label most of their projected labels and its own agree on; ties "
      "keep its own). In every table **Reference is the projected labels**, the same for all three "
      "settings of one projection: the vote only changes the rows after it (M, N, M-N, M-R-N), so its "
      "effect is counted in their change from Reference, as the other modes' are.")
    w("")

    # Summary.
    w("## Summary")
    w("")
    w("| 2D labels | projection | Reference BIoU | M-R-N BIoU | Δ BIoU | Δ lower arms | largest body-class change | smallest body-class change |")
    w("|---|---|---:|---:|---:|---:|---|---|")
    for (source, mode), rows in runs.items():
        d_biou, per_class = gains(rows)
        best = max(per_class, key=per_class.get)
        worst = min(per_class, key=per_class.get)
        w(f"| {source_name[source]} | {mode_name[mode]} | {rows['Reference']['biou']:.2f} | "
          f"{rows['M-R-N']['biou']:.2f} | {d_biou:+.2f} | {per_class['lower_arms']:+.2f} | "
          f"{best} {per_class[best]:+.2f} | {worst} {per_class[worst]:+.2f} |")
    w("")
    w(f"The paper (synthetic data, its Table 1): M-R-N BIoU {PAPER_GAIN['biou']:+.2f}, lower arms "
      f"{PAPER_GAIN['lower_arms']:+.2f} IoU, the largest gain of all classes.")
    w("")

    # Reading.
    w("## What matches the paper, what does not, and why")
    w("")
    paper_setting = runs[("recorded", "naive")]
    d_biou, per_class = gains(paper_setting)
    best = max(per_class, key=per_class.get)
    w(f"- **The paper's setting** (synthetic parser errors, naive projection): M-R-N changes BIoU by "
      f"{d_biou:+.2f} and lower arms by {per_class['lower_arms']:+.2f} IoU; the largest gain is on "
      f"{best.replace('_', ' ')} ({per_class[best]:+.2f})."
      + (" As in the paper, the refinement helps and the small parts gain most." if d_biou > 0 and best in ("lower_arms", "lower_legs", "upper_arms") else
         " This differs from the paper: see the points below."))
    if best != "lower_arms":
        w(why_not_lower_arms(paper_setting, best))
    for source in ["recorded", "model"]:
        rows = runs[(source, "dsa")]
        d, pc = gains(rows)
        n_gain = rows["N"]["biou"] - rows["Reference"]["biou"]
        w(f"- **DSA projection, {source_name[source]}**: M-R-N {d:+.2f} BIoU, of which N alone gives "
          f"{n_gain:+.2f}. DSA leaves the points it cannot trust unknown; Reference scores them as "
          f"background, and N gives them the label of the nearest cluster. So with DSA the refinement also "
          f"completes the projection, and its gain is larger than in the paper's setting, where every point "
          f"has a (possibly wrong) label.")
    for source in ["recorded", "model"]:
        rows = runs[(source, "dsa")]
        m_gain = rows["M"]["biou"] - rows["Reference"]["biou"]
        r_gain = rows["M-R-N"]["biou"] - rows["M-N"]["biou"]
        w(f"- **The steps one by one** ({source_name[source]}, DSA): M {m_gain:+.2f} BIoU; R on top of M-N "
          f"{r_gain:+.2f}. R only removes clusters cut off from the body tree; on these recordings such "
          f"clusters are rare (the person boxes already drop what lies outside them), so R changes little, "
          f"as the paper's small M-N → M-R-N step also shows.")
    for source in ["recorded", "model"]:
        for mode in ["naive", "dsa"]:
            base, imp, d0, d1, pc1, ratio = against_paper(runs, source, mode, "improved")
            losses = [c for c in BODY if pc1[c] < -0.5]
            r_step = imp["M-R-N"]["biou"] - imp["M-N"]["biou"]
            w(f"- **Improved refinement** ({source_name[source]}, {mode_name[mode]}): M-R-N {d1:+.2f} BIoU against "
              f"the paper mode's {d0:+.2f} (×{ratio:.2f}); M-N {imp['M-N']['biou'] - imp['Reference']['biou']:+.2f}, "
              f"so R changes it by {r_step:+.2f}"
              + (" (R turns body clusters that the contact graph finds cut off from the body tree into "
                 "background; some were real body parts)" if r_step < -0.1 else "")
              + ("; no body class loses more than 0.5 IoU." if not losses else
                 f"; {', '.join(losses)} lose more than 0.5 IoU.")
              + (" The issue's target (at least twice the paper mode's gain) is met." if ratio >= 2 else
                 f" The issue's target (at least twice the paper mode's gain) is not met: it needs M-R-N BIoU "
                 f"{base['Reference']['biou'] + 2 * d0:.2f} ({2 * d0:.2f} of the "
                 f"{100.0 - base['Reference']['biou']:.2f} points left between Reference and 100)."))
    for mode in ["naive", "dsa"]:
        d_w, pc_w = gains(weighted[mode])
        d_p, pc_p = gains(runs[("model", f"{mode}_improved")])
        d0, _ = gains(runs[("model", mode)])
        w(f"- **What the parser's probabilities add** (bundled ONNX model, {mode_name[mode]}): the improved "
          f"refinement with `noise = \"weighted\"` (no probabilities, "
          f"[`improved_weighted.toml`](../configs/benchmarks/improved_weighted.toml)) gains {d_w:+.2f} BIoU "
          f"(×{d_w / d0:.2f} the paper mode's), with `noise = \"probability\"` {d_p:+.2f} (×{d_p / d0:.2f}); "
          f"lower arms {pc_w['lower_arms']:+.2f} → {pc_p['lower_arms']:+.2f} IoU. "
          + ("The probabilities help BIoU here: " if d_p > d_w else "The probabilities do not help BIoU here: ")
          + "labels the model doubted no longer form clusters of their own that M and N "
          "keep, and N gives them the label of the sure points around them"
          + ("; the lower-arm loss says that where a whole small part is unsure, the larger sure parts "
             "next to it (upper arm, torso) outvote it." if pc_p["lower_arms"] < pc_w["lower_arms"] else ".")
          + " (`noise_doubt_ratio` = 0.85 and `noise_doubt_radius_m` = 0.15 were chosen on recordings "
          "outside the benchmark; "
          "see configs/benchmarks/improved.toml.)")
    for source in ["recorded", "model"]:
        for mode in ["naive", "dsa"]:
            base, vote, d0, d1, pc1, ratio = against_paper(runs, source, mode, "vote")
            worst = min(pc1, key=pc1.get)
            ceiling = 100.0 - base["Reference"]["biou"]  # BIoU points left to repair
            d_imp, _ = gains(runs[(source, f"{mode}_improved")])
            extra = f" (improved refinement without the vote: {d_imp:+.2f}, so the vote changes it by {d1 - d_imp:+.2f})"
            m_base = base["M"]["biou"] - base["Reference"]["biou"]
            m_vote = vote["M"]["biou"] - vote["Reference"]["biou"]
            w(f"- **Improved refinement + multi-view vote** ({source_name[source]}, {mode_name[mode]}): M-R-N "
              f"{d1:+.2f} BIoU against the paper mode's {d0:+.2f} (×{ratio:.2f}){extra}; the smallest body-class "
              f"change is {worst} {pc1[worst]:+.2f} IoU"
              + (" (no body class loses more than 0.5 IoU)." if pc1[worst] >= -0.5 else " (a loss of more than 0.5 IoU).")
              + f" M alone, which starts from the voted labels, gains {m_vote:+.2f} against the paper's {m_base:+.2f}."
              + (" The issue's target (at least twice the paper mode's gain) is met." if ratio >= 2 else
                 f" The issue's target (at least twice the paper mode's gain) is not met: it needs M-R-N BIoU "
                 f"{base['Reference']['biou'] + 2 * d0:.2f}"
                 + (f", more than is left to repair ({ceiling:.2f} points from Reference to 100)." if 2 * d0 > ceiling else
                    f" ({2 * d0:.2f} of the {ceiling:.2f} points left between Reference and 100).")
                 + " The vote repairs what one view gets wrong and the others right (a part missed, swapped or "
                   "bled over in one view) where at least two other views see the point; the N step already "
                   "fills most of the same points from their neighbours, and the errors every view makes alike "
                   "(small parts grown into their neighbours, boundaries) stay."))
    w("")

    blazepose_section(w, work, runs)

    # Projection study.
    proj = (work / "projection.md").read_text().strip()
    w("## Projection: DSA against naive")
    w("")
    w("Perfect 2D labels (the truth), so every wrong point is a depth-segmentation association error; "
      "10 frames per preset, with and without a calibration error (0.5°, 1 cm), "
      "`cargo run --release -p bodyseg-lab --example projection_report 10`:")
    w("")
    w(proj)
    w("")
    cut = []
    for line in proj.splitlines():
        cells = [c.strip() for c in line.strip("|").split("|")]
        if len(cells) > 5 and cells[3].endswith("%") and cells[4].endswith("%"):
            naive, dsa = float(cells[3][:-1]), float(cells[4][:-1])
            if naive > 0:
                cut.append(1 - dsa / naive)
    if cut:
        w(f"DSA cuts the wrongly labelled points by {100 * min(cut):.0f}–{100 * max(cut):.0f}% against naive "
          f"(the issue asks ≥ 50%); the price is the points it leaves unknown (column DSA unknown).")
        w("")

    # Tables.
    w("## Tables (the paper's layout)")
    w("")
    for (source, mode), rows in runs.items():
        w(f"### {source_name[source]}, {mode_name[mode]}")
        w("")
        w(table(rows))
        w("")

    w("## Figures")
    w("")
    w("Frame 12 of `handover` seed 2005 (synthetic parser errors, DSA): input labels, DBSCAN clusters, "
      "M, N, M-N, M-R-N and the truth, from one viewpoint. Paper mode, then the improved refinement.")
    w("")
    w("![paper mode](images/results_paper.png)")
    w("")
    w("![improved refinement](images/results_improved.png)")
    w("")
    w("The same frame with the default parser (BlazePose on the people found from depth, BodyPix's "
      "parts; paper mode, DSA): the two people of the hand-over overlap in the views and are "
      "labelled as one: the front person's head takes the torso label of the person behind.")
    w("")
    w("![BlazePose, paper mode](images/results_blazepose.png)")
    w("")
    w('Real organised RGB-D frame, the default parser (BlazePose full on the people found from depth, body parts from BodyPix): PCL\'s `test/five_people.pcd`, five people seen from behind; every person gets a region and parts (labels over the image; [notes](notes/2026-12-04-bodypix-probe.md); BlazePose alone: [image](images/five_people_blazepose.png), [notes](notes/2026-12-02-blazepose-segmenter.md)). Its rows on the synthetic benchmark are above; on real photographs, the table below.')
    w('')
    w('![five_people, BlazePose + BodyPix](images/five_people_bodypix.png)')
    w('')
    # The real-photograph scores come from their own commands (kept in the fragment, with
    # the figures), not from reproduce.sh: copied in so that this page stays whole.
    real = Path(__file__).resolve().parent.parent / "docs" / "results_real_photographs.md"
    if real.exists():
        w(real.read_text().rstrip("\n"))
        w('')

    w("## Regression subset")
    w("")
    w("The first seed of each preset, first 4 frames, synthetic parser errors, DSA, paper configuration "
      "(`tests/results_regression.rs` checks this figure within ±0.2):")
    w("")
    w(f"regression-subset M-R-N BIoU: {subset['M-R-N']['biou']:.2f}")
    w("")
    print("\n".join(out))


if __name__ == "__main__":
    main()
