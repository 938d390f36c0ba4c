"""The desktop viewer's side panel: material, solver, light and display controls, and the status, beside the view.

The panel holds widgets only. Each control emits one signal with the value the user chose; the window
(:mod:`translucency.app.desktop.window`) turns it into a change of the viewer's state, and :meth:`SidePanel.show_state`
puts the controls where the state is without emitting anything.
"""

from __future__ import annotations

import contextlib
import math

from PySide6 import QtCore, QtWidgets

from ...scatter.names import MAX_BOUNCES, MODELS
from ..viewer.state import ViewerState

#: The tolerances the panel offers (relative error per vertex, docs/physics.md §8.4); any other can be typed.
TOLERANCES = (0.003, 0.01, 0.03, 0.1)
#: Half-range of the exposure slider, stops (log2) around the first exposure; its step is a tenth of a stop.
EXPOSURE_STOPS = 8.0
#: The kinds of light the panel builds (:func:`translucency.app.desktop.lighting.panel_lights`).
LIGHT_KINDS = ("directional", "point", "environment")
#: Units a scan's file may be in (the unit combo; "inferred" keeps what loading chose).
UNITS = ("mm", "cm", "m", "in")
#: Width of the panel, pixels.
PANEL_WIDTH = 330


def _row(*widgets) -> QtWidgets.QWidget:
    """Widgets side by side in one row."""
    row = QtWidgets.QWidget()
    layout = QtWidgets.QHBoxLayout(row)
    layout.setContentsMargins(0, 0, 0, 0)
    for widget in widgets:
        layout.addWidget(widget)
    return row


class MaterialChooser(QtWidgets.QGroupBox):
    """The material group: a searchable list of the catalogue's scattering materials and the user's own
    material files, and a material of one's own from its diffuse reflectance and mean free path.
    ``material_chosen(object)`` carries a catalogue key, a material file's path or a definition mapping."""

    material_chosen = QtCore.Signal(object)

    def __init__(self, parent=None):
        from ...scatter.materials import catalogue
        from ..shading.settings import user_material_files

        super().__init__("Material", parent)
        layout = QtWidgets.QVBoxLayout(self)
        #: Filters the material list as it is typed (name, key or source).
        self.material_search = QtWidgets.QLineEdit()
        self.material_search.setPlaceholderText("search materials (e.g. milk, marble, skin)")
        self.material_search.setClearButtonEnabled(True)
        #: The catalogue's scattering materials and the user's own material files.
        self.material_list = QtWidgets.QListWidget()
        self.material_list.setFixedHeight(150)
        for entry in catalogue():
            if not entry.is_diffusive:
                continue
            item = QtWidgets.QListWidgetItem(entry.name)
            item.setData(QtCore.Qt.UserRole, entry.key)
            item.setToolTip(f"{entry.key}: {entry.source}")
            self.material_list.addItem(item)
        for key, path in sorted(user_material_files().items()):
            item = QtWidgets.QListWidgetItem(f"{key} (your own)")
            item.setData(QtCore.Qt.UserRole, str(path))
            item.setToolTip(str(path))
            self.material_list.addItem(item)
        self.material_search.textChanged.connect(self._filter_materials)
        self.material_list.itemActivated.connect(self._material_item)
        self.material_list.itemClicked.connect(self._material_item)
        layout.addWidget(self.material_search)
        layout.addWidget(self.material_list)
        # a material of one's own: diffuse reflectance and mean free path
        self.reflectance = QtWidgets.QLineEdit("0.8, 0.6, 0.4")
        self.reflectance.setToolTip("diffuse reflectance per channel, each strictly between 0 and 1 (one or R, G, B)")
        self.mfp = QtWidgets.QDoubleSpinBox()
        self.mfp.setRange(0.001, 1000.0)
        self.mfp.setDecimals(3)
        self.mfp.setValue(1.0)
        self.mfp.setSuffix(" mm")
        self.mfp.setToolTip("mean free path 1/sigma_t', mm")
        use = QtWidgets.QPushButton("Use")
        use.setToolTip("shade with this reflectance and mean free path")
        use.clicked.connect(self._own_material)
        form = QtWidgets.QFormLayout()
        form.addRow("reflectance", self.reflectance)
        form.addRow("mean free path", _row(self.mfp, use))
        layout.addLayout(form)

    def select(self, key: str) -> None:
        """Highlight the material ``key`` in the list (none: nothing), without a signal."""
        self.material_list.blockSignals(True)
        for row in range(self.material_list.count()):
            item = self.material_list.item(row)
            if item.data(QtCore.Qt.UserRole) == key:
                self.material_list.setCurrentItem(item)
                break
        else:
            self.material_list.clearSelection()
        self.material_list.blockSignals(False)

    def _filter_materials(self, text: str) -> None:
        words = text.lower().split()
        for row in range(self.material_list.count()):
            item = self.material_list.item(row)
            haystack = f"{item.text()} {item.data(QtCore.Qt.UserRole)} {item.toolTip()}".lower()
            item.setHidden(not all(word in haystack for word in words))

    def _material_item(self, item) -> None:
        self.material_chosen.emit(item.data(QtCore.Qt.UserRole))

    def _own_material(self) -> None:
        text = self.reflectance.text().replace(" ", "")
        try:
            values = [float(part) for part in text.split(",")]
        except ValueError:
            values = []
        # the definition is checked where it is made, with a sentence on a bad one (translucency.scatter.definition)
        reflectance = values[0] if len(values) == 1 else values if values else text
        self.material_chosen.emit({"reflectance": reflectance, "mfp": self.mfp.value(), "name": "own material"})


@contextlib.contextmanager
def quiet(widgets):
    """Within the block, ``widgets`` send no signal (the panel shows a state it did not choose)."""
    for widget in widgets:
        widget.blockSignals(True)
    try:
        yield
    finally:
        for widget in widgets:
            widget.blockSignals(False)


class SidePanel(QtWidgets.QWidget):
    """The controls beside the view (in a scroll area, so that a small window never hides one) and the status
    under them.

    Signals carry the chosen value: ``material_chosen(object)`` (a catalogue key, a material file's path or
    a definition mapping), ``model_chosen(str)``, ``tol_chosen(float)``, ``bounces_chosen(int)``,
    ``unit_chosen(str)``, ``light_chosen(str, float, float, float)`` (kind, azimuth and elevation in degrees,
    distance in radii of the scan), ``exposure_chosen(float)`` (linear factor),
    ``false_colour_chosen(bool, str, str)`` (on, quantity, scale), ``view_dependent_chosen(bool)`` and
    ``specular_chosen(bool)``.
    """

    material_chosen = QtCore.Signal(object)
    model_chosen = QtCore.Signal(str)
    tol_chosen = QtCore.Signal(float)
    bounces_chosen = QtCore.Signal(int)
    unit_chosen = QtCore.Signal(str)
    light_chosen = QtCore.Signal(str, float, float, float)
    exposure_chosen = QtCore.Signal(float)
    false_colour_chosen = QtCore.Signal(bool, str, str)
    view_dependent_chosen = QtCore.Signal(bool)
    specular_chosen = QtCore.Signal(bool)

    def __init__(self, parent=None):
        super().__init__(parent)
        self.setMinimumWidth(PANEL_WIDTH)
        scroll = QtWidgets.QScrollArea()
        scroll.setWidgetResizable(True)
        scroll.setHorizontalScrollBarPolicy(QtCore.Qt.ScrollBarAlwaysOff)
        scroll.setFrameShape(QtWidgets.QFrame.NoFrame)
        body = QtWidgets.QWidget()
        layout = QtWidgets.QVBoxLayout(body)
        #: The material group (:class:`MaterialChooser`).
        self.materials = MaterialChooser()
        self.materials.material_chosen.connect(self.material_chosen)
        layout.addWidget(self.materials)
        layout.addWidget(self._solver_box())
        layout.addWidget(self._light_box())
        layout.addWidget(self._display_box())
        layout.addStretch(1)
        scroll.setWidget(body)
        status = QtWidgets.QGroupBox("Status")
        status_layout = QtWidgets.QVBoxLayout(status)
        #: What was solved, how, at what tolerance, and the time per frame.
        self.status = QtWidgets.QLabel("no scan yet")
        self.status.setWordWrap(True)
        self.status.setTextInteractionFlags(QtCore.Qt.TextSelectableByMouse)
        self.status.setObjectName("status")
        self.status.setAlignment(QtCore.Qt.AlignTop | QtCore.Qt.AlignLeft)
        status_layout.addWidget(self.status)
        outer = QtWidgets.QVBoxLayout(self)
        outer.setContentsMargins(0, 0, 0, 0)
        outer.addWidget(scroll, 1)
        outer.addWidget(status)
        self._exposure_centre = 0.0

    # ------------------------------------------------------------------------------------------------
    # the groups

    def _solver_box(self) -> QtWidgets.QGroupBox:
        box = QtWidgets.QGroupBox("Solver")
        form = QtWidgets.QFormLayout(box)
        self.model = QtWidgets.QComboBox()
        self.model.addItems(list(MODELS))
        self.model.setToolTip("the BSSRDF: directional dipole (Frisvad et al. 2014), standard or better dipole")
        self.model.currentTextChanged.connect(self.model_chosen)
        self.tol = QtWidgets.QComboBox()
        self.tol.setEditable(True)
        self.tol.addItems([f"{t:g}" for t in TOLERANCES])
        self.tol.setToolTip("relative error per vertex at the 99th percentile; smaller is slower")
        self.tol.activated.connect(lambda _: self._tol_entered())
        self.tol.lineEdit().editingFinished.connect(self._tol_entered)
        self.bounces = QtWidgets.QSpinBox()
        self.bounces.setRange(0, MAX_BOUNCES)
        self.bounces.setToolTip("how many times light that leaves the surface enters it again")
        self.bounces.valueChanged.connect(self.bounces_chosen)
        self.unit = QtWidgets.QComboBox()
        self.unit.addItems(list(UNITS))
        self.unit.setToolTip("the length unit of the scan's file (sets its size in mm)")
        self.unit.activated.connect(lambda _: self.unit_chosen.emit(self.unit.currentText()))
        form.addRow("model", self.model)
        form.addRow("tolerance", self.tol)
        form.addRow("bounces", self.bounces)
        form.addRow("file unit", self.unit)
        return box

    def _light_box(self) -> QtWidgets.QGroupBox:
        box = QtWidgets.QGroupBox("Light (drag the yellow ball in the view)")
        form = QtWidgets.QFormLayout(box)
        self.light_kind = QtWidgets.QComboBox()
        self.light_kind.addItems(list(LIGHT_KINDS))
        self.light_kind.setToolTip(
            "directional: the sun; point: a lamp at the distance below; environment: white from every direction"
        )
        self.azimuth = QtWidgets.QDoubleSpinBox()
        self.azimuth.setRange(-180.0, 180.0)
        self.azimuth.setWrapping(True)
        self.azimuth.setSuffix(" deg")
        self.azimuth.setToolTip("around the scan's up axis")
        self.elevation = QtWidgets.QDoubleSpinBox()
        self.elevation.setRange(-90.0, 90.0)
        self.elevation.setSuffix(" deg")
        self.elevation.setToolTip("above the plane across the up axis")
        self.distance = QtWidgets.QDoubleSpinBox()
        self.distance.setRange(1.05, 100.0)
        self.distance.setValue(3.0)
        self.distance.setSingleStep(0.5)
        self.distance.setSuffix(" radii")
        self.distance.setToolTip("a point light's distance from the scan's centre, in radii of its bounding sphere")
        for widget in (self.azimuth, self.elevation, self.distance):
            widget.setKeyboardTracking(False)
            widget.valueChanged.connect(lambda _: self._light_entered())
        self.light_kind.currentTextChanged.connect(lambda _: self._light_entered())
        form.addRow("kind", self.light_kind)
        form.addRow("azimuth", self.azimuth)
        form.addRow("elevation", self.elevation)
        form.addRow("distance", self.distance)
        return box

    def _display_box(self) -> QtWidgets.QGroupBox:
        box = QtWidgets.QGroupBox("Display")
        form = QtWidgets.QFormLayout(box)
        self.exposure = QtWidgets.QSlider(QtCore.Qt.Horizontal)
        self.exposure.setRange(-int(10 * EXPOSURE_STOPS), int(10 * EXPOSURE_STOPS))
        self.exposure.setToolTip("display exposure in stops around the first one (no new solve)")
        self.exposure_label = QtWidgets.QLabel("")
        self.exposure.valueChanged.connect(self._exposure_moved)
        self.false_colour = QtWidgets.QCheckBox("false colour (y)")
        self.false_colour.setToolTip("the radiance in W/(m² sr) per W/m² through a colour map, with its colour bar")
        self.quantity = QtWidgets.QComboBox()
        self.quantity.addItems(["luminance", "red", "green", "blue"])
        self.scale = QtWidgets.QComboBox()
        self.scale.addItems(["log", "linear"])
        self.scale.setToolTip("log: three decades below white; linear: from 0 (key l swaps them)")
        for signal in (self.false_colour.toggled, self.quantity.currentTextChanged, self.scale.currentTextChanged):
            signal.connect(lambda _: self._false_colour_entered())
        self.view_dependent = QtWidgets.QCheckBox("transmission toward the camera")
        self.view_dependent.setToolTip("T21(eta, n.w_o) B: darker at grazing angles, as seen from the camera")
        self.view_dependent.toggled.connect(self.view_dependent_chosen)
        self.specular = QtWidgets.QCheckBox("specular highlight")
        self.specular.setToolTip("the boundary's GGX reflection of the directional lights")
        self.specular.toggled.connect(self.specular_chosen)
        form.addRow("exposure", _row(self.exposure, self.exposure_label))
        form.addRow(self.false_colour)
        form.addRow("shows", _row(self.quantity, self.scale))
        form.addRow(self.view_dependent)
        form.addRow(self.specular)
        return box

    # ------------------------------------------------------------------------------------------------
    # the state shown, without a signal

    def show_settings(self, settings, unit: str | None) -> None:
        """The solver's controls where the starting ``settings`` (a ShadeSettings) and file ``unit`` (None: left
        as it is, inferred when the scan loads) put them, before a scan is loaded; no signal is sent."""
        with quiet((self.model, self.tol, self.bounces, self.unit)):
            self._show_solver(settings.model, settings.tol, settings.bounces, unit)

    def _show_solver(self, model: str, tol: float, bounces: int, unit: str | None) -> None:
        self.model.setCurrentText(model)
        self.tol.setEditText(f"{tol:g}")
        self.bounces.setValue(int(bounces))
        if unit is not None and self.unit.findText(str(unit)) >= 0:
            self.unit.setCurrentText(str(unit))

    def show_state(self, state: ViewerState, light_kind: str, distance: float, unit: str) -> None:
        """Every control where ``state`` (and the window's light kind, point distance and unit) are."""
        widgets = (
            self.model,
            self.tol,
            self.bounces,
            self.unit,
            self.light_kind,
            self.azimuth,
            self.elevation,
            self.distance,
            self.exposure,
            self.false_colour,
            self.quantity,
            self.scale,
            self.view_dependent,
            self.specular,
        )
        with quiet(widgets):
            self._show_solver(state.model, state.tol, state.bounces, unit)
            self.light_kind.setCurrentText(light_kind)
            if state.azimuth is not None:
                self.azimuth.setValue(state.azimuth)
                self.elevation.setValue(state.elevation)
            self.distance.setValue(distance)
            self.distance.setEnabled(light_kind == "point")
            for widget in (self.azimuth, self.elevation):
                widget.setEnabled(light_kind != "environment")
            if state.exposure is not None:
                if self._exposure_centre == 0.0:
                    self._exposure_centre = math.log2(state.exposure)
                self.exposure.setValue(round(10 * (math.log2(state.exposure) - self._exposure_centre)))
                self.exposure_label.setText(f"{state.exposure:.3g}")
            self.false_colour.setChecked(state.false_colour)
            self.quantity.setCurrentText(state.false_colour_quantity)
            self.scale.setCurrentText(state.false_colour_scale)
            self.view_dependent.setChecked(state.view_dependent)
            self.specular.setChecked(state.specular)
            self.materials.select(state.medium.name)

    def set_angles(self, azimuth: float, elevation: float) -> None:
        """Show the light's angles (degrees) as the handle in the view is dragged, without a signal."""
        for widget, value in ((self.azimuth, azimuth), (self.elevation, elevation)):
            widget.blockSignals(True)
            widget.setValue(value)
            widget.blockSignals(False)

    def reset_exposure(self) -> None:
        """Centre the exposure slider on the next exposure shown (a new scan)."""
        self._exposure_centre = 0.0

    # ------------------------------------------------------------------------------------------------
    # user input to signals

    def _tol_entered(self) -> None:
        try:
            tol = float(self.tol.currentText())
        except ValueError:
            tol = math.nan  # the window says what a tolerance must be
        self.tol_chosen.emit(tol)

    def _light_entered(self) -> None:
        kind = self.light_kind.currentText()
        self.distance.setEnabled(kind == "point")
        for widget in (self.azimuth, self.elevation):
            widget.setEnabled(kind != "environment")
        self.light_chosen.emit(kind, self.azimuth.value(), self.elevation.value(), self.distance.value())

    def _exposure_moved(self, value: int) -> None:
        exposure = 2.0 ** (self._exposure_centre + value / 10.0)
        self.exposure_label.setText(f"{exposure:.3g}")
        self.exposure_chosen.emit(exposure)

    def _false_colour_entered(self) -> None:
        self.false_colour_chosen.emit(
            self.false_colour.isChecked(), self.quantity.currentText(), self.scale.currentText()
        )
