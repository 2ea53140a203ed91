#!/usr/bin/env python3
"""Turns the grids tests/ssdo_light.rs writes (VRAO_SSDO_IMAGES=DIR) into one PNG per eye:
SSDO's ambient light without and with the bounce, its bounce, the reference's bounce and
the reference's ambient light, side by side, on one exposure (the reference ambient's
99th percentile maps to white), sRGB-encoded. usage: ssdo-images.py DIR OUT.png [scale]"""
import sys
import numpy as np
from PIL import Image

folder, out = sys.argv[1], sys.argv[2]
scale = int(sys.argv[3]) if len(sys.argv) > 3 else 3
names = ["ssdo", "ssdo-bounce", "bounce", "reference-bounce", "reference-ambient"]


def grid(name, layer):
    w, h = map(int, open(f"{folder}/{name}-{layer}.txt").read().split())
    return np.fromfile(f"{folder}/{name}-{layer}.bin", dtype="<f4").reshape(h, w, 3)


rows = []
for layer in (0, 1):
    images = [grid(n, layer) for n in names]
    white = np.percentile(images[-1], 99) or 1.0
    tiles = []
    for im in images:
        v = np.clip(im / white, 0, 1)
        v = np.where(v <= 0.0031308, 12.92 * v, 1.055 * np.power(v, 1 / 2.4) - 0.055)
        tiles.append((v * 255 + 0.5).astype(np.uint8))
        tiles.append(np.full((im.shape[0], 2, 3), 255, np.uint8))
    rows.append(np.concatenate(tiles[:-1], axis=1))
image = np.concatenate([rows[0], np.full((2, rows[0].shape[1], 3), 255, np.uint8), rows[1]], axis=0)
Image.fromarray(image).resize((image.shape[1] * scale, image.shape[0] * scale), Image.NEAREST).save(out)
print(f"{out}: {' | '.join(names)} (top: left eye, bottom: right eye)")
