"""Mean NVIDIA FLIP error of an image against a reference (flip-evaluator).

    python -m portico_quality.flip IMAGE REFERENCE

Prints `flip MEAN` (0: identical, 1: as different as can be). Linear images
(.exr, .hdr) are compared as HDR-FLIP, which tone-maps both over the range of
exposures the reference asks for; PNG/JPEG as LDR-FLIP. Exits 3 when
flip-evaluator is not installed (deploy/install-deps.sh puts it in .venv),
2 when the images cannot be compared.
"""
import os
import sys

HDR = {".exr", ".hdr"}
LDR = {".png", ".jpg", ".jpeg"}


def dynamic_range(path):
    extension = os.path.splitext(path)[1].lower()
    if extension in HDR:
        return "HDR"
    if extension in LDR:
        return "LDR"
    raise ValueError(f"{path}: FLIP reads .exr, .hdr, .png or .jpg")


def main(argv):
    if len(argv) != 3:
        print("usage: python -m portico_quality.flip IMAGE REFERENCE", file=sys.stderr)
        return 2
    image, reference = argv[1], argv[2]
    try:
        import flip_evaluator
    except ImportError:
        print("flip-evaluator is not installed (deploy/install-deps.sh installs it into .venv)", file=sys.stderr)
        return 3
    try:
        kind = dynamic_range(image)
        if dynamic_range(reference) != kind:
            raise ValueError(f"{image} and {reference}: one is HDR, the other LDR")
        for path in (image, reference):
            if not os.path.isfile(path):
                raise ValueError(f"{path}: no such file")
        _, mean, _ = flip_evaluator.evaluate(reference, image, kind, applyMagma=False)
    except (ValueError, RuntimeError) as error:
        print(f"portico_quality.flip: {error}", file=sys.stderr)
        return 2
    print(f"flip {mean:.6f}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
