"""Bias and noise of renders against a reference, per 16x16 block.

    python -m portico_quality.block_bias REFERENCE IMAGE [IMAGE ...] [--map]

The IMAGEs are renders of one view that differ only in their --seed. Each
block's signed relative error (block mean of R, G, B against the
reference's, blocks under 5 % of the reference's image mean skipped: as
portico-compare) is taken per image; a block's **bias** is its mean over the
images, its **noise** their standard deviation. Prints one line: the image
mean's error, the RMS, mean and largest |bias| over the blocks, how many are
past 1 %, the RMS noise and each image's block RMSE; --map adds the bias of
every block (% , rows top to bottom, '.' for a skipped block).

The bias seen includes the reference's own noise, and noise / sqrt(images):
docs/image-bias.md says how large they were. EXR files are read with
flip-evaluator's loader (deploy/install-deps.sh installs it in .venv).
"""
import sys

import numpy as np

BLOCK = 16
SKIPPED_BELOW = 0.05  # of the reference's image mean, as portico-compare


def block_means(image):
    h, w = image.shape[0] // BLOCK * BLOCK, image.shape[1] // BLOCK * BLOCK
    return image[:h, :w].mean(axis=2).reshape(h // BLOCK, BLOCK, w // BLOCK, BLOCK).mean(axis=(1, 3))


def block_errors(reference, images):
    """Per image, the signed relative error of each block; and which blocks count."""
    ref = block_means(reference)
    checked = ref > SKIPPED_BELOW * reference.mean()
    errors = np.array([(block_means(image) - ref) / np.where(ref > 0, ref, 1) for image in images])
    return errors, checked


def summary(reference, images):
    errors, checked = block_errors(reference, images)
    bias = errors.mean(axis=0)[checked]
    noise = errors.std(axis=0, ddof=1)[checked] if len(images) > 1 else np.zeros_like(bias)
    mean_error = np.mean([image.mean() / reference.mean() - 1 for image in images])
    rmse = " ".join(f"{np.sqrt((e[checked] ** 2).mean()) * 100:.2f}" for e in errors)
    return (f"{len(images)} images, {int(checked.sum())} blocks: image mean {mean_error * 100:+.2f} %; "
            f"bias RMS {np.sqrt((bias ** 2).mean()) * 100:.2f} % (mean {bias.mean() * 100:+.2f} %, "
            f"largest {np.abs(bias).max() * 100:.1f} %, {int((np.abs(bias) > 0.01).sum())} blocks past 1 %); "
            f"noise RMS {np.sqrt((noise ** 2).mean()) * 100:.2f} %; block RMSE {rmse} %")


def bias_map(reference, images):
    errors, checked = block_errors(reference, images)
    bias = errors.mean(axis=0)
    return "\n".join(" ".join(f"{bias[r, c] * 100:+5.1f}" if checked[r, c] else "    ." for c in range(bias.shape[1]))
                     for r in range(bias.shape[0]))


def main(argv):
    show_map = "--map" in argv
    paths = [a for a in argv[1:] if a != "--map"]
    if len(paths) < 2:
        print("usage: python -m portico_quality.block_bias REFERENCE IMAGE [IMAGE ...] [--map]", file=sys.stderr)
        return 2
    try:
        import flip_evaluator
    except ImportError:
        print("flip-evaluator is not installed (deploy/install-deps.sh installs it into .venv)", file=sys.stderr)
        return 3
    try:
        reference, *images = [np.asarray(flip_evaluator.load(p), dtype=np.float64)[..., :3] for p in paths]
    except (RuntimeError, ValueError) as error:
        print(f"portico_quality.block_bias: {error}", file=sys.stderr)
        return 2
    for path, image in zip(paths[1:], images):
        if image.shape != reference.shape:
            print(f"portico_quality.block_bias: {path} is {image.shape[1]}x{image.shape[0]}, the reference "
                  f"{reference.shape[1]}x{reference.shape[0]}", file=sys.stderr)
            return 2
    print(summary(reference, images))
    if show_map:
        print(bias_map(reference, images))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
