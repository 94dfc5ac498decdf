"""The window's status bar: its message elided to the room the task widgets leave, whole in the tooltip.

Qt's status bar draws a message clipped at the first permanent widget, so a running task's stage label
cut "scores of the edited curve shown; defects updating…" to "…shown; defect" on a small screen
(docs/guide/viewer.md "Sessions and small screens"). Here the message ends in "…" when it does not fit,
and its full text is the bar's tooltip; ``currentMessage()`` stays the full text.
"""

from __future__ import annotations

from PySide6 import QtCore, QtGui, QtWidgets

#: the message's margins: Qt's own (QStatusBarPrivate::messageRect) on the left and the right, and a
#: gap before a widget wider than Qt's 2 px, so that an elided message does not run into the stage
LEFT_MARGIN, WIDGET_GAP, RIGHT_MARGIN = 6, 12, 12


class StatusBar(QtWidgets.QStatusBar):
    """A status bar whose temporary message never runs under its permanent widgets."""

    def __init__(self, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self._permanent: list[QtWidgets.QWidget] = []
        self.messageChanged.connect(lambda _text: self._update_tooltip())

    def addPermanentWidget(self, widget: QtWidgets.QWidget, stretch: int = 0) -> None:  # noqa: N802
        super().addPermanentWidget(widget, stretch)
        self._permanent.append(widget)
        widget.installEventFilter(self)  # its showing or hiding changes the message's room

    def eventFilter(self, watched: QtCore.QObject, event: QtCore.QEvent) -> bool:  # noqa: N802
        if event.type() in (QtCore.QEvent.Type.Show, QtCore.QEvent.Type.Hide, QtCore.QEvent.Type.Move):
            self._update_tooltip()
        return False

    def message_rect(self) -> QtCore.QRect:
        """The room for the message: from Qt's left margin to just before the first visible permanent
        widget (or the bar's right margin)."""
        right = self.width() - RIGHT_MARGIN
        shown = [w.x() for w in self._permanent if w.isVisible()]
        if shown:
            right = min(right, min(shown) - WIDGET_GAP)
        return QtCore.QRect(LEFT_MARGIN, 0, max(0, right - LEFT_MARGIN), self.height())

    def shown_message(self) -> str:
        """The message as drawn: whole if it fits its room, else elided with "…"."""
        return self.fontMetrics().elidedText(self.currentMessage(), QtCore.Qt.TextElideMode.ElideRight,
                                             self.message_rect().width())

    def _update_tooltip(self) -> None:
        text = self.currentMessage()
        tip = text if text and self.shown_message() != text else ""
        if self.toolTip() != tip:
            self.setToolTip(tip)

    def resizeEvent(self, event: QtGui.QResizeEvent) -> None:  # noqa: N802
        super().resizeEvent(event)
        self._update_tooltip()

    def paintEvent(self, event: QtGui.QPaintEvent) -> None:  # noqa: N802
        """Qt's painting (the panel, the permanent widgets' frames) with the message elided."""
        text = self.currentMessage()
        if not text:
            super().paintEvent(event)
            return
        p = QtGui.QPainter(self)
        opt = QtWidgets.QStyleOption()
        opt.initFrom(self)
        self.style().drawPrimitive(QtWidgets.QStyle.PrimitiveElement.PE_PanelStatusBar, opt, p, self)
        for w in self._permanent:
            if w.isVisible():
                item = QtWidgets.QStyleOption()
                item.rect = w.geometry().adjusted(-2, -1, 2, 1)
                item.palette = self.palette()
                item.state = QtWidgets.QStyle.StateFlag.State_None
                self.style().drawPrimitive(QtWidgets.QStyle.PrimitiveElement.PE_FrameStatusBarItem, item, p, w)
        p.setPen(self.palette().windowText().color())
        flags = (QtCore.Qt.AlignmentFlag.AlignLeading | QtCore.Qt.AlignmentFlag.AlignVCenter
                 | QtCore.Qt.TextFlag.TextSingleLine)
        p.drawText(self.message_rect(), flags, self.shown_message())
        p.end()
