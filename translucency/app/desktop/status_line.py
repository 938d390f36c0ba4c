"""The desktop viewer's status bar: one line of text, and the running solve's progress with its Cancel button."""

from __future__ import annotations

from PySide6 import QtWidgets

#: Steps of the progress bar.
PROGRESS_STEPS = 1000


class StatusLine(QtWidgets.QStatusBar):
    """A status bar with a message (:meth:`say`) and, while a solve runs (:meth:`show_busy`), its progress and a
    Cancel button that calls ``cancel()``."""

    def __init__(self, cancel, parent=None):
        super().__init__(parent)
        #: The one line of text.
        self.message = QtWidgets.QLabel("")
        self.progress_bar = QtWidgets.QProgressBar()
        self.progress_bar.setMinimumWidth(260)
        self.progress_bar.setRange(0, PROGRESS_STEPS)
        self.cancel_button = QtWidgets.QPushButton("Cancel")
        self.cancel_button.setToolTip("stop the running solve (Esc); the picture stays as it was")
        self.cancel_button.clicked.connect(cancel)
        self.addWidget(self.message, 1)
        self.addPermanentWidget(self.progress_bar)
        self.addPermanentWidget(self.cancel_button)
        self.show_busy(False)

    def say(self, text: str) -> None:
        """Show ``text`` (one line)."""
        self.message.setText(text)

    def show_busy(self, busy: bool) -> None:
        """Show the progress bar (from 0) and the Cancel button while a solve runs; hide them after."""
        if busy:
            self.progress_bar.setValue(0)
            self.progress_bar.setFormat("%p%")
        self.progress_bar.setVisible(busy)
        self.cancel_button.setVisible(busy)

    def show_progress(self, stage: str, fraction: float) -> None:
        """The running solve's ``stage`` and how much of it is done (0 to 1)."""
        self.progress_bar.setValue(int(PROGRESS_STEPS * max(0.0, min(1.0, fraction))))
        self.progress_bar.setFormat(f"{stage} %p%")
