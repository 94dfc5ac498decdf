"""The Qt binding the viewer runs on must survive many signal emissions.

PySide6-Essentials 6.12.0 drops a reference to ``True`` on every ``Signal.emit`` and aborts the
process after a few hundred progress updates; pyproject.toml excludes it. This pins that.
"""

import subprocess
import sys

SCRIPT = """
import sys
from PySide6.QtCore import QCoreApplication, QObject, Signal
app = QCoreApplication([])
class Emitter(QObject):
    progress = Signal(float, str)
e = Emitter(); seen = []
e.progress.connect(lambda f, s: seen.append(f))
before = sys.getrefcount(True)
for _ in range(3000):
    e.progress.emit(0.5, "stage")
print(len(seen), sys.getrefcount(True) - before)
"""


def test_thousands_of_signal_emits_do_not_leak_or_abort():
    proc = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-500:]
    seen, leaked = map(int, proc.stdout.split())
    assert seen == 3000
    assert abs(leaked) < 100
