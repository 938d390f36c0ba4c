"""Draw the README's pictures of the desktop viewer: ``docs/images/viewer.png`` and ``viewer_false_colour.png``.

Run under a display (``xvfb-run -a -s "-screen 0 1600x1000x24" .venv/bin/python docs/make_screenshots.py``):
it opens the viewer on the embedded default bunny in marble, waits for its solves, moves the light behind the
bunny's right ear (through the panel, as a user would), and grabs the whole window; then turns false colour
on and grabs it again.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

from PySide6 import QtWidgets

#: Where the pictures go.
IMAGES = Path(__file__).resolve().parent / "images"
#: Window size, pixels.
WINDOW = (1280, 800)
#: The light: from behind and to the right of the camera, above (degrees around the scan's up axis).
BACK_LIGHT = (-150.0, 25.0)
#: Longest wait for a solve, s.
WAIT_S = 600


def _wait(app, window, started=None):
    deadline = time.monotonic() + WAIT_S
    while time.monotonic() < deadline:
        app.processEvents()
        time.sleep(0.05)
        settled = window.state is not None and window.state.result is not None and not window.jobs.busy
        if settled and (started is None or window.state.n_solves > started):
            for _ in range(20):  # the last job's signals, and a paint
                app.processEvents()
                time.sleep(0.02)
            return
    sys.exit("the viewer did not finish solving in time")


def main() -> None:
    from translucency.app.desktop import MainWindow

    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(["translucency"])
    window = MainWindow(None, window_size=WINDOW)
    window.show()
    _wait(app, window)
    solves = window.state.n_solves
    window.panel.azimuth.setValue(BACK_LIGHT[0])
    window.panel.elevation.setValue(BACK_LIGHT[1])
    _wait(app, window, solves)
    IMAGES.mkdir(exist_ok=True)
    window.grab().save(str(IMAGES / "viewer.png"))
    window.panel.false_colour.setChecked(True)
    for _ in range(20):
        app.processEvents()
        time.sleep(0.02)
    window.grab().save(str(IMAGES / "viewer_false_colour.png"))
    window.close()
    print(f"wrote {IMAGES / 'viewer.png'} and {IMAGES / 'viewer_false_colour.png'}")


if __name__ == "__main__":
    main()
