#!/usr/bin/env python3
"""Real photographs with pixel-level body-part ground truth, extracted from local snapshots of
public repositories (issue 29, part 4). The images' licences are unclear (PASCAL VOC / COCO
photographs from Flickr), so none is committed: tests/fixtures/real_parsing/manifest.json
names each file by repository, commit, path and git blob hash, and this script extracts them
into the git-ignored folder .data/real_parsing/.

    python3 scripts/real_parsing_data.py                      # snapshots under /work/.mirror
    python3 scripts/real_parsing_data.py --repo Charleshhy/Grapy-ML=~/src/Grapy-ML ...

A snapshot is a clone (working tree or bare/mirror git directory) of the repository at the
manifest's commit or later; each file is checked against its blob hash.

Output (.data/real_parsing/):
  images/<name>.jpg          the photograph, bytes as in the repository
  labels/<name>.png          8-bit ground truth in the manifest item's scheme (below)
  index.json                 name, label set, scheme, source and person boxes of each item:
                             [x0, y0, x1, y1] inclusive pixel centres, from the annotation's
                             person objects (pascal_part) or from the connected parts of the
                             ground-truth person mask (the others, which have no instances).
                             They stand in for the boxes bodyseg finds from depth.
                             "split": "holdout" for items the manifest marks so (images
                             added after the rule was tuned, never looked at while tuning;
                             scripts/score_parsing.py --split holdout), else absent.

Schemes:
  "parts7"  exact Pascal-Person-Part classes (shared/ALGORITHM.md §0: 0 background, 1 head,
            2 torso, 3 upper_arms, 4 lower_arms, 5 upper_legs, 6 lower_legs), 255 = not labelled.
  "super5"  coarse ground truth (LIP/CIHP/ATR): 0 background, 1 head, 2 torso / upper
            clothes, 7 arms (upper + lower), 8 legs (upper + lower), 255 = not labelled
            (garments spanning several parts: dress, skirt, jumpsuit, scarf, belt, bag).

Label sets and their mapping:
  ppp_ids       Pascal-Person-Part PNG as released (pascal_person_part_gt, palette mode): the
                pixel values are our class ids 0-6 directly (read off the four images of
                light-weight-refinenet's examples: the shoulder-elbow segment is 3, the
                forearm and hand 4, the thigh 5, the shin and foot 6); other values -> 255.
  ppp_palette   Pascal-Person-Part PNG in VOC palette colours (Graphonomy / Grapy-ML
                layout, SegmentationPart/): each pixel -> the nearest of the 7 colours of
                PPP_PALETTE (the limbs' colours are not in ALGORITHM.md §0's order; see there).
  pascal_part   PASCAL-Part MATLAB annotation (Annotations_Part/*.mat, Chen et al. 2014):
                person parts merged as Pascal-Person-Part does: head = head, hair, eyes, ears,
                eyebrows, nose, mouth; torso = torso; upper arms = luarm, ruarm; lower arms =
                llarm, rlarm, lhand, rhand; upper legs = luleg, ruleg; lower legs = llleg,
                rlleg, lfoot, rfoot. The neck is not labelled (255): Pascal-Person-Part's own
                choice for it is not documented in the sources here. Person pixels outside
                every part are 255; other objects are background.
  cihp / lip    20 classes (CIHP_PGN, LIP): head = hat, hair, sunglasses, face; torso =
                upper-clothes, coat; arms = glove, left/right arm; legs = pants, socks,
                left/right leg, left/right shoe; 255 = dress, jumpsuits, scarf, skirt.
  atr           18 classes: head = hat, hair, sunglasses, face; torso = upper-clothes;
                arms = left/right arm; legs = pants, left/right leg, left/right shoe;
                255 = skirt, dress, belt, bag, scarf.
"""

import argparse
import hashlib
import io
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
MANIFEST = ROOT / "tests" / "fixtures" / "real_parsing" / "manifest.json"
DEFAULT_OUT = ROOT / ".data" / "real_parsing"
MIRROR = Path("/work/.mirror")

IGNORE = 255
SUPER_ARMS, SUPER_LEGS = 7, 8

# Colours of the Grapy-ML Pascal-Person-Part PNGs, indexed by our class id. They are the
# VOC palette colours, but not in ALGORITHM.md §0's order for the limbs: in these files the
# shoulder-elbow segment carries (0, 0, 128) and the forearm and hand (128, 128, 0); the
# thigh (0, 128, 128) and the shin and foot (128, 0, 128). Read off the images (a jockey's
# horizontal thigh and hanging shin, a seated man's thigh and shin, arms holding a puppy,
# a woman sitting in a boat), on every limb of the 8 images.
PPP_PALETTE = np.array([[0, 0, 0], [128, 0, 0], [0, 128, 0], [0, 0, 128],
                        [128, 128, 0], [0, 128, 128], [128, 0, 128]], np.int32)
# A pixel whose colour is farther than this (RGB Euclidean) from every palette colour is
# not labelled; the Grapy-ML PNGs carry colours like (126, 1, 128), 2-3 away.
PPP_MAX_COLOUR_DIST = 40.0

PASCAL_PART_TO_PARTS7 = {
    "head": 1, "hair": 1, "leye": 1, "reye": 1, "lear": 1, "rear": 1, "lebrow": 1,
    "rebrow": 1, "nose": 1, "mouth": 1,
    "torso": 2, "neck": IGNORE,
    "luarm": 3, "ruarm": 3,
    "llarm": 4, "rlarm": 4, "lhand": 4, "rhand": 4,
    "luleg": 5, "ruleg": 5,
    "llleg": 6, "rlleg": 6, "lfoot": 6, "rfoot": 6,
}
CIHP_TO_SUPER = {0: 0, 1: 1, 2: 1, 3: SUPER_ARMS, 4: 1, 5: 2, 6: IGNORE, 7: 2, 8: SUPER_LEGS,
                 9: SUPER_LEGS, 10: IGNORE, 11: IGNORE, 12: IGNORE, 13: 1, 14: SUPER_ARMS,
                 15: SUPER_ARMS, 16: SUPER_LEGS, 17: SUPER_LEGS, 18: SUPER_LEGS, 19: SUPER_LEGS}
ATR_TO_SUPER = {0: 0, 1: 1, 2: 1, 3: 1, 4: 2, 5: IGNORE, 6: SUPER_LEGS, 7: IGNORE, 8: IGNORE,
                9: SUPER_LEGS, 10: SUPER_LEGS, 11: 1, 12: SUPER_LEGS, 13: SUPER_LEGS,
                14: SUPER_ARMS, 15: SUPER_ARMS, 16: IGNORE, 17: IGNORE}
PPP_IDS = {k: k for k in range(7)}
SCHEME = {"ppp_ids": "parts7", "ppp_palette": "parts7", "pascal_part": "parts7", "cihp": "super5", "lip": "super5",
          "atr": "super5"}


def git_blob_sha(data):
    return hashlib.sha1(b"blob %d\0" % len(data) + data).hexdigest()


def git_dir_of(path):
    p = Path(path)
    if (p / ".git").exists():
        return p / ".git"
    if (p / "HEAD").exists() and (p / "objects").exists():
        return p
    return None


def read_blob(snapshot, rel_path, blob):
    """The file's bytes from a snapshot (git directory: by blob hash; working tree: by
    path), checked against the manifest's blob hash."""
    gd = git_dir_of(snapshot)
    if gd is not None:
        r = subprocess.run(["git", "--git-dir", str(gd), "cat-file", "blob", blob],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        if r.returncode == 0:
            data = r.stdout
        elif (Path(snapshot) / rel_path).exists():
            data = (Path(snapshot) / rel_path).read_bytes()
        else:
            raise FileNotFoundError(f"{snapshot}: blob {blob} ({rel_path}) not in the snapshot")
    else:
        data = (Path(snapshot) / rel_path).read_bytes()
    got = git_blob_sha(data)
    if got != blob:
        raise ValueError(f"{snapshot}/{rel_path}: blob hash {got}, manifest says {blob}")
    return data


def labels_ppp_palette(data):
    from PIL import Image

    rgb = np.asarray(Image.open(io.BytesIO(data)).convert("RGB"), np.int32)
    d = np.linalg.norm(rgb[:, :, None, :] - PPP_PALETTE[None, None], axis=-1)
    ids = d.argmin(-1).astype(np.uint8)
    ids[d.min(-1) > PPP_MAX_COLOUR_DIST] = IGNORE
    return ids


def labels_pascal_part(data):
    """(labels, person boxes from the annotation's person objects)."""
    import scipy.io as sio

    anno = sio.loadmat(io.BytesIO(data), squeeze_me=True, struct_as_record=False)["anno"]
    objects = np.atleast_1d(anno.objects)
    shape = np.asarray(objects[0].mask).shape
    out = np.zeros(shape, np.uint8)
    boxes = []
    for obj in objects:
        if getattr(obj, "class") != "person":
            continue
        mask = np.asarray(obj.mask) > 0
        out[mask] = IGNORE
        boxes.append(mask_box(mask))
        parts = np.atleast_1d(obj.parts) if np.size(obj.parts) else []
        for part in parts:
            cls = PASCAL_PART_TO_PARTS7.get(part.part_name)
            if cls is None:
                raise ValueError(f"pascal_part: unknown person part {part.part_name!r}")
            out[np.asarray(part.mask) > 0] = cls
    return out, [bx for bx in boxes if bx is not None]


def mask_box(mask):
    """[x0, y0, x1, y1] (inclusive pixel centres) of a boolean mask, None when empty."""
    ys, xs = np.nonzero(mask)
    if xs.size == 0:
        return None
    return [int(xs.min()), int(ys.min()), int(xs.max()), int(ys.max())]


# A connected part of the ground-truth person mask smaller than this fraction of the image
# gives no person box (a hand or a foot cut off by an occluder stays with its neighbours'
# boxes, or is missed).
MIN_COMPONENT_FRACTION = 0.002
CROSS = np.array([[0, 1, 0], [1, 1, 1], [0, 1, 0]], bool)


def component_boxes(labels):
    """Person boxes of a ground truth without instances. People touching in the image form
    one connected person mask, so the mask is divided between its heads first (as bodyseg's
    labels-mode boxes divide a cluster between heads): each head (connected part of the head
    class, 8-neighbour, at least MIN_COMPONENT_FRACTION / 4 of the image) grows through the
    person mask (any id but 0) one 4-neighbour step at a time (so the reach is the city-block
    distance inside the mask; 8-neighbour steps would tie everywhere below two heads); a
    pixel goes to the head that reaches it first (ties: the lower head number). What no head reaches forms boxes of its
    own connected parts (closed by 2 px). Parts smaller than MIN_COMPONENT_FRACTION of the
    image give no box."""
    from scipy import ndimage

    person = labels != 0
    heads, n_heads = ndimage.label(labels == 1, structure=np.ones((3, 3)))
    seeds = np.zeros(labels.shape, np.int32)
    k = 0
    for i in range(1, n_heads + 1):
        m = heads == i
        if m.sum() >= MIN_COMPONENT_FRACTION / 4 * labels.size:
            k += 1
            seeds[m] = k
    owner = seeds.copy()
    while k:
        free = person & (owner == 0)
        # smallest neighbouring owner id > 0: grey erosion of ids with 0 read as "none"
        ids = np.where(owner > 0, owner, np.iinfo(np.int32).max)
        grown = ndimage.grey_erosion(ids, footprint=CROSS)
        take = free & (grown < np.iinfo(np.int32).max)
        if not take.any():
            break
        owner[take] = grown[take]
    boxes = []
    for i in range(1, k + 1):
        m = owner == i
        if m.sum() >= MIN_COMPONENT_FRACTION * labels.size:
            boxes.append(mask_box(m))
    rest = person & (owner == 0)
    joined = ndimage.binary_dilation(rest, iterations=2)
    comp, n = ndimage.label(joined, structure=np.ones((3, 3)))
    for i in range(1, n + 1):
        m = (comp == i) & rest
        if m.sum() >= MIN_COMPONENT_FRACTION * labels.size:
            boxes.append(mask_box(m))
    return boxes


def labels_table(data, table):
    from PIL import Image

    ids = np.asarray(Image.open(io.BytesIO(data)))
    if ids.ndim != 2:
        raise ValueError("expected an 8-bit class-id PNG")
    lut = np.full(256, IGNORE, np.uint8)
    for k, v in table.items():
        lut[k] = v
    return lut[ids]


def convert_labels(label_set, data):
    """(labels in the item's scheme, person boxes [x0, y0, x1, y1])."""
    if label_set == "pascal_part":
        return labels_pascal_part(data)
    if label_set == "ppp_palette":
        labels = labels_ppp_palette(data)
    elif label_set == "ppp_ids":
        labels = labels_table(data, PPP_IDS)
    elif label_set in ("cihp", "lip"):
        labels = labels_table(data, CIHP_TO_SUPER)
    elif label_set == "atr":
        labels = labels_table(data, ATR_TO_SUPER)
    else:
        raise ValueError(f"unknown label set {label_set!r}")
    return labels, component_boxes(labels)


def write_atomic(path, data):
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_bytes(data)
    os.replace(tmp, path)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--manifest", default=str(MANIFEST))
    ap.add_argument("--out", default=str(DEFAULT_OUT))
    ap.add_argument("--repo", action="append", default=[],
                    help="owner/name=PATH of a local snapshot (default /work/.mirror/owner+name/repo)")
    args = ap.parse_args()

    from PIL import Image

    manifest = json.loads(Path(args.manifest).read_text())
    snapshots = dict(r.split("=", 1) for r in args.repo)
    out = Path(args.out)
    (out / "images").mkdir(parents=True, exist_ok=True)
    (out / "labels").mkdir(parents=True, exist_ok=True)
    index, missing = [], []
    for src in manifest["sources"]:
        repo = src["repository"]
        snap = snapshots.get(repo) or str(MIRROR / repo.replace("/", "+") / "repo")
        if not Path(snap).exists():
            missing.append(repo)
            continue
        for item in src["items"]:
            img = read_blob(snap, item["image"], item["image_blob"])
            lab, boxes = convert_labels(item["label_set"], read_blob(snap, item["labels"], item["labels_blob"]))
            w, h = Image.open(io.BytesIO(img)).size
            if lab.shape != (h, w):
                raise ValueError(f"{repo}/{item['labels']}: labels {lab.shape[::-1]} but image {w}x{h}")
            write_atomic(out / "images" / f"{item['name']}.jpg", img)
            buf = io.BytesIO()
            Image.fromarray(lab).save(buf, format="PNG")
            write_atomic(out / "labels" / f"{item['name']}.png", buf.getvalue())
            entry = {"name": item["name"], "label_set": item["label_set"],
                     "scheme": SCHEME[item["label_set"]], "repository": repo,
                     "commit": src["commit"], "image": item["image"], "labels": item["labels"],
                     "person_boxes": boxes}
            split = item.get("split", src.get("split"))
            if split is not None:
                entry["split"] = split
            index.append(entry)
    index.sort(key=lambda r: r["name"])
    write_atomic(out / "index.json", (json.dumps(index, indent=1) + "\n").encode())
    exact = sum(r["scheme"] == "parts7" for r in index)
    print(f"{out}: {len(index)} images ({exact} exact 7-class, {len(index) - exact} coarse)")
    for repo in missing:
        print(f"missing snapshot of {repo}: pass --repo {repo}=PATH", file=sys.stderr)
    return 1 if missing else 0


if __name__ == "__main__":
    sys.exit(main())
