"""The findings as cards: effect, evidence, every other field the diagnosis gives, and the evidence plot."""

from __future__ import annotations

from PySide6.QtWidgets import QFrame, QLabel, QPushButton, QScrollArea, QVBoxLayout, QWidget

from workbench.gui import diagnosis_views as views
from workbench.gui.widgets.plot_view import ViewPlot

__all__ = ["FindingCard", "FindingCards"]


class FindingCard(QFrame):
    """One finding (a :class:`~workbench.gui.diagnosis_views.FindingCard`)."""

    def __init__(self, card, parent=None):
        super().__init__(parent)
        self.card = card
        self.setFrameShape(QFrame.Shape.StyledPanel)
        self.setStyleSheet("FindingCard{background:#fbfbf8;border:1px solid #d8d4c8;border-radius:6px}")
        layout = QVBoxLayout(self)
        title = QLabel(f"<b>{card.effect}</b>")
        evidence = QLabel(card.evidence)
        evidence.setWordWrap(True)
        fields = QLabel("<br>".join(f"<span style='color:#666'>{name}</span>: {text}" for name, text in card.fields))
        fields.setWordWrap(True)
        layout.addWidget(title)
        layout.addWidget(evidence)
        layout.addWidget(fields)
        self.plot = None
        if card.plot is not None:
            self.plot = ViewPlot(legend=len(card.plot.series) > 1)
            self.plot.setMinimumHeight(170)
            self.plot.show_view(card.plot)
            layout.addWidget(self.plot)
        self.action = None

    def add_action(self, button: QPushButton) -> None:
        """Put ``button`` (e.g. "Measure the N patches that identify this") at the foot of the card."""
        self.action = button
        self.layout().addWidget(button)


class FindingCards(QScrollArea):
    """The cards of a diagnosis, strongest finding first (the diagnosis's order)."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self.setWidgetResizable(True)
        self.setMinimumWidth(330)
        self.cards: list = []
        self.action_button: QPushButton | None = None
        self._action = None
        self._set_body(QLabel("No diagnosis yet: calibrate, or open a session (File ▸ Open)."))

    def set_action(self, effects, text: str, tooltip: str, callback) -> None:
        """On the next :meth:`show_diagnosis`, a button ``text`` on the card of the first finding
        among ``effects`` (above the cards where no card is one of them); None: no button."""
        self._action = None if effects is None else (tuple(effects), text, tooltip, callback)

    def _set_body(self, *widgets) -> None:
        old = self.takeWidget()  # deleted by Qt now, not whenever Python collects it
        if old is not None:
            old.deleteLater()
        body = QWidget()
        layout = QVBoxLayout(body)
        for widget in widgets:
            layout.addWidget(widget)
        layout.addStretch(1)
        self.setWidget(body)

    def show_diagnosis(self, diagnosis) -> None:
        if diagnosis is None:
            self.cards = []
            self._set_body(QLabel("No diagnosis yet: calibrate, or open a session (File ▸ Open)."))
            return
        self.cards = [FindingCard(card) for card in views.finding_cards(diagnosis)]
        self.action_button = None
        standalone = []
        if self._action is not None:
            effects, text, tooltip, callback = self._action
            self.action_button = QPushButton(text)
            self.action_button.setObjectName("follow-up-button")
            self.action_button.setToolTip(tooltip)
            self.action_button.clicked.connect(lambda checked=False: callback())
            card = next((c for c in self.cards if c.card.effect in effects), None)
            if card is not None:
                card.add_action(self.action_button)
            else:
                standalone.append(self.action_button)
        if not self.cards:
            self._set_body(*standalone, QLabel("No finding beyond noise: the paper's model is adequate for "
                                               "this display."))
            return
        self._set_body(*standalone, *self.cards)
