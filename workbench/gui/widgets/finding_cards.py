"""The findings as cards: effect, evidence, every other field the diagnosis gives, and the evidence plot.

Above the cards, the model the profile exports: each candidate's cross-validated mean ΔE00 in a
table, the exported one marked, and why it was chosen. A finding another finding explains (its
``consequence_of``) follows its cause's card, indented and tagged "consequence of CAUSE". Every text
wraps to the width of the column; nothing in a card is wider than the narrowest column.
"""

from __future__ import annotations

from PySide6.QtCore import QSize, Qt
from PySide6.QtGui import QBrush, QColor, QFont
from PySide6.QtWidgets import (
    QAbstractItemView,
    QFrame,
    QHBoxLayout,
    QHeaderView,
    QLabel,
    QPushButton,
    QScrollArea,
    QSizePolicy,
    QStyle,
    QStyleOptionButton,
    QStylePainter,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from workbench.gui import diagnosis_views as views
from workbench.gui.widgets.plot_view import ViewPlot

__all__ = ["FindingCard", "FindingCards", "ModelChoiceTable", "WrappingButton", "CONSEQUENCE_INDENT"]

CONSEQUENCE_INDENT = 22
"""Pixels a consequence's card is indented under its cause's."""

_CHOSEN_BACKGROUND = "#e6f0dc"

_CARD_PLOT_MAX_HEIGHT = 210
"""Pixels: the tallest a card's evidence plot is drawn."""


class WrappingButton(QPushButton):
    """A push button whose text wraps to the width it is given; ``text()`` is the whole text.

    A plain QPushButton is as wide as its text on one line, which made a card wider than the
    column and clipped every line on it.
    """

    _PAD = 6

    def __init__(self, text: str = "", parent=None):
        super().__init__(text, parent)
        self._label = QLabel(text, self)
        self._label.setWordWrap(True)
        self._label.setAlignment(Qt.AlignmentFlag.AlignCenter)
        self._label.setAttribute(Qt.WidgetAttribute.WA_TransparentForMouseEvents)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(self._PAD, self._PAD, self._PAD, self._PAD)
        layout.addWidget(self._label)
        policy = QSizePolicy(QSizePolicy.Policy.Preferred, QSizePolicy.Policy.Preferred)
        policy.setHeightForWidth(True)
        self.setSizePolicy(policy)

    def setText(self, text: str) -> None:  # noqa: N802 - Qt's name
        super().setText(text)
        self._label.setText(text)

    def label(self) -> QLabel:
        """The label that shows the text."""
        return self._label

    def hasHeightForWidth(self) -> bool:  # noqa: N802 - Qt's name
        return True

    def heightForWidth(self, width: int) -> int:  # noqa: N802 - Qt's name
        return self._label.heightForWidth(max(1, width - 2 * self._PAD)) + 2 * self._PAD

    def minimumSizeHint(self) -> QSize:  # noqa: N802 - Qt's name
        hint = self._label.minimumSizeHint()
        return QSize(hint.width() + 2 * self._PAD, hint.height() + 2 * self._PAD)

    def sizeHint(self) -> QSize:  # noqa: N802 - Qt's name
        width = super().sizeHint().width()
        return QSize(width, self.heightForWidth(width))

    def paintEvent(self, event) -> None:  # noqa: N802 - Qt's name
        painter = QStylePainter(self)
        option = QStyleOptionButton()
        self.initStyleOption(option)
        option.text = ""  # the label draws it, wrapped
        painter.drawControl(QStyle.ControlElement.CE_PushButton, option)


class FindingCard(QFrame):
    """One finding (a :class:`~workbench.gui.diagnosis_views.FindingCard`).

    A consequence of another finding carries a "consequence of CAUSE" tag under its title and
    the reason, split off its evidence, below it; the cause's card says which findings it explains.
    """

    def __init__(self, card, parent=None):
        super().__init__(parent)
        self.card = card
        self.setFrameShape(QFrame.Shape.StyledPanel)
        consequence = bool(card.consequence_of)
        background, border = ("#f6f5f0", "#c9c2ad") if consequence else ("#fbfbf8", "#d8d4c8")
        self.setStyleSheet(f"FindingCard{{background:{background};border:1px solid {border};"
                           f"border-radius:6px}}")
        layout = QVBoxLayout(self)
        title = QLabel(f"<b>{card.effect}</b>")
        title.setWordWrap(True)
        layout.addWidget(title)
        self.tag = None
        if consequence:
            self.tag = QLabel(f"consequence of <b>{card.consequence_of}</b>")
            self.tag.setObjectName("consequence-tag")
            self.tag.setStyleSheet("QLabel{background:#ece6d6;border-radius:3px;padding:1px 6px;color:#4a4535}")
            self.tag.setSizePolicy(QSizePolicy.Policy.Maximum, QSizePolicy.Policy.Fixed)
            layout.addWidget(self.tag)
        if card.consequences:
            explains = QLabel("explains " + ", ".join(f"<b>{e}</b>" for e in card.consequences)
                              + " (below, indented)")
            explains.setObjectName("consequences")
            explains.setWordWrap(True)
            explains.setStyleSheet("QLabel{color:#4a4535}")
            layout.addWidget(explains)
        self.evidence = QLabel(card.evidence)
        self.evidence.setWordWrap(True)
        self.evidence.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        layout.addWidget(self.evidence)
        self.why = None
        if card.consequence:
            self.why = QLabel(f"← {card.consequence}")
            self.why.setWordWrap(True)
            self.why.setStyleSheet("QLabel{color:#555;font-style:italic}")
            layout.addWidget(self.why)
        fields = QLabel("<br>".join(f"<span style='color:#666'>{name}</span>: {text}" for name, text in card.fields))
        fields.setWordWrap(True)
        layout.addWidget(fields)
        self.plot = None
        if card.plot is not None:
            self.plot = ViewPlot(legend=len(card.plot.series) > 1)
            self.plot.setMinimumHeight(170)
            self.plot.setMaximumHeight(_CARD_PLOT_MAX_HEIGHT)  # a card, not a page: the next card shows
            self.plot.show_view(card.plot)
            layout.addWidget(self.plot)
        self.action = None

    def add_action(self, button: QPushButton) -> None:
        """Put ``button`` (e.g. "Measure the N patches that identify this") at the foot of the card."""
        self.action = button
        self.layout().addWidget(button)


class ModelChoiceTable(QTableWidget):
    """The candidates the exported model was chosen among: cross-validated mean ΔE00, the chosen marked.

    Columns: model and its mean ΔE00 (cross-validated on the fit rows; "—" where not scored).
    The exported model's row reads "✓ NAME", bold on a tint. Each row's tooltip says what the
    model is. As tall as its rows: it sits in the scrolling column of cards and never scrolls itself.
    """

    COLUMNS = ("model", "CV mean ΔE00")
    MARK = "✓ "
    """Before the exported model's name."""

    def __init__(self, parent=None):
        super().__init__(0, len(self.COLUMNS), parent)
        self.setHorizontalHeaderLabels(self.COLUMNS)
        self.horizontalHeaderItem(1).setToolTip("mean ΔE00 of the candidate's cross-validated predictions "
                                                "of the fit rows (never the validation colours)")
        self.setEditTriggers(QAbstractItemView.EditTrigger.NoEditTriggers)
        self.setSelectionMode(QAbstractItemView.SelectionMode.NoSelection)
        self.setFocusPolicy(Qt.FocusPolicy.NoFocus)
        self.verticalHeader().setVisible(False)
        header = self.horizontalHeader()
        header.setSectionResizeMode(0, QHeaderView.ResizeMode.ResizeToContents)
        header.setSectionResizeMode(1, QHeaderView.ResizeMode.Stretch)
        self.setVerticalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        self.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Fixed)
        self.rows: tuple = ()

    def show_rows(self, rows) -> None:
        """Fill the table with :class:`~workbench.gui.diagnosis_views.ModelChoiceRow` s."""
        self.rows = tuple(rows)
        self.setRowCount(len(self.rows))
        for i, row in enumerate(self.rows):
            value = "—" if row.cv_mean_dE00 is None else f"{row.cv_mean_dE00:.3f}"
            cells = (QTableWidgetItem((self.MARK if row.chosen else "") + row.candidate),
                     QTableWidgetItem(value))
            cells[1].setTextAlignment(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
            for column, cell in enumerate(cells):
                cell.setToolTip(("exported: " if row.chosen else "") + row.description)
                if row.chosen:
                    font = QFont(cell.font())
                    font.setBold(True)
                    cell.setFont(font)
                    cell.setBackground(QBrush(QColor(_CHOSEN_BACKGROUND)))
                self.setItem(i, column, cell)
        self.resizeColumnsToContents()
        self.resizeRowsToContents()
        height = self.horizontalHeader().sizeHint().height() + 2 * self.frameWidth()
        height += sum(self.rowHeight(i) for i in range(self.rowCount()))
        self.setFixedHeight(height + 2)

    def chosen_row(self) -> int:
        """The row of the exported model (-1 where none)."""
        return next((i for i, row in enumerate(self.rows) if row.chosen), -1)


class _ModelChoiceBox(QFrame):
    """A caption, the :class:`ModelChoiceTable` and the reason the exported model was chosen."""

    def __init__(self, rows, reason: str, parent=None):
        super().__init__(parent)
        self.setObjectName("model-choice")
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 4)
        chosen = next((r.candidate for r in rows if r.chosen), "")
        caption = QLabel(f"<b>Exported model: {chosen}</b> (✓), chosen by each candidate's mean ΔE00 "
                         "cross-validated on the fit rows")
        caption.setWordWrap(True)
        self.table = ModelChoiceTable()
        self.table.show_rows(rows)
        self.reason = QLabel(reason)
        self.reason.setWordWrap(True)
        self.reason.setStyleSheet("QLabel{color:#444}")
        self.reason.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        for widget in (caption, self.table, self.reason):
            layout.addWidget(widget)


def _wrapped(text: str) -> QLabel:
    label = QLabel(text)
    label.setWordWrap(True)
    return label


class FindingCards(QScrollArea):
    """The exported model's choice, then the cards of a diagnosis, strongest finding first (the
    diagnosis's order), each consequence indented after its cause."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self.setWidgetResizable(True)
        self.setMinimumWidth(330)
        self.cards: list = []
        self.model_choice: ModelChoiceTable | None = None
        self.model_reason: QLabel | None = None
        self.action_button: QPushButton | None = None
        self._action = None
        self._set_body(_wrapped("No diagnosis yet: calibrate, or open a session (File ▸ Open)."))

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

    @staticmethod
    def _placed(card: FindingCard) -> QWidget:
        """``card``, indented under its cause where it is a consequence."""
        if not card.card.consequence_of:
            return card
        holder = QWidget()
        row = QHBoxLayout(holder)
        row.setContentsMargins(CONSEQUENCE_INDENT, 0, 0, 0)
        row.addWidget(card)
        return holder

    def show_diagnosis(self, diagnosis) -> None:
        for _ in self.drawing_steps(diagnosis):
            pass

    def drawing_steps(self, diagnosis):
        """:meth:`show_diagnosis` a part at a time: a generator that yields after the cards' contents
        are read from ``diagnosis`` and after each card is built (a card's plot is tens of
        milliseconds), and ends with them in place of the old ones, which stay shown until then."""
        if diagnosis is None:
            self.model_choice = self.model_reason = None
            self.cards = []
            self._set_body(_wrapped("No diagnosis yet: calibrate, or open a session (File ▸ Open)."))
            return
        contents = views.finding_cards(diagnosis)
        yield
        cards = []
        for content in contents:
            cards.append(FindingCard(content))
            yield
        self.model_choice = self.model_reason = None
        self.cards = cards
        self.action_button = None
        standalone = []
        rows = views.model_choice_rows(diagnosis)
        if rows:
            box = _ModelChoiceBox(rows, views.model_choice_reason(diagnosis))
            self.model_choice, self.model_reason = box.table, box.reason
            standalone.append(box)
        if self._action is not None:
            effects, text, tooltip, callback = self._action
            self.action_button = WrappingButton(text)
            self.action_button.setObjectName("follow-up-button")
            self.action_button.setToolTip(tooltip)
            self.action_button.clicked.connect(lambda checked=False: callback())
            card = next((c for c in self.cards if c.card.effect in effects), None)
            if card is not None:
                card.add_action(self.action_button)
            else:
                standalone.append(self.action_button)
        if not self.cards:
            self._set_body(*standalone, _wrapped("No finding beyond noise: the paper's model is adequate "
                                                 "for this display."))
            return
        self._set_body(*standalone, *(self._placed(card) for card in self.cards))
