"""Mitsuba 3 renders of portico's reference scenes (tests/scenes), beside portico's own.

`portico bench quality SCENE_DIR --mitsuba` runs `python -m portico_mitsuba`
in the virtual environment `deploy/install-deps.sh --peers` makes, and
scores its images as it scores portico's (docs/image-quality.md).
"""
