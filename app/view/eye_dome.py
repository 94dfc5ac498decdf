"""Eye-dome lighting of the 3-D scene only: the 2-D overlays (the colour bar, its title and NaN legend,
the legends, the hint) are drawn on top of it, as crisp as without it.

pyvista's ``enable_eye_dome_lighting`` shades everything its renderer draws, the 2-D actors included,
which smeared the colour bar's and the legends' text. Here the renderer's shading delegates to VTK's
standard render steps without their overlay step, and a renderer of its own on the layer above draws
the 2-D actors (the same actors: they are taken from the main renderer before every frame, so every
module keeps adding and removing its overlays there), with blending on again (the shading leaves it
off, which drew the text's antialiased edges solid).
"""

from __future__ import annotations

from typing import Any

__all__ = ["EyeDome"]


class EyeDome:
    """Eye-dome lighting of ``plotter``'s renderer, switched with :meth:`set`."""

    def __init__(self, plotter: Any) -> None:
        self.plotter = plotter
        self.overlay: Any = None  # the renderer of the 2-D actors while the lighting is on
        self._observer: int | None = None
        self._pass: Any = None

    @property
    def on(self) -> bool:
        return self.overlay is not None

    def set(self, on: bool) -> None:
        if bool(on) == self.on:
            return
        ren = self.plotter.renderer
        win = self.plotter.ren_win
        if on:
            from vtkmodules.vtkRenderingCore import vtkRenderer

            self._pass = _scene_only_pass()
            ren.SetPass(self._pass)
            overlay = vtkRenderer()
            overlay.SetLayer(max(2, win.GetNumberOfLayers()))  # above the orientation axes' layer 1
            overlay.SetViewport(ren.GetViewport())
            overlay.InteractiveOff()
            overlay.SetPreserveColorBuffer(True)
            overlay.SetPreserveDepthBuffer(False)
            win.SetNumberOfLayers(max(win.GetNumberOfLayers(), overlay.GetLayer() + 1))
            win.AddRenderer(overlay)
            overlay.AddObserver("StartEvent", lambda *_: _blend_again(win))
            self.overlay = overlay
            self._observer = ren.AddObserver("StartEvent", lambda *_: self.sync())
            self.sync()
        else:
            self._pass.ReleaseGraphicsResources(win)
            self._pass = None
            ren.SetPass(None)
            if self._observer is not None:
                ren.RemoveObserver(self._observer)
                self._observer = None
            self.overlay.RemoveAllViewProps()
            win.RemoveRenderer(self.overlay)
            self.overlay = None

    def close(self) -> None:
        """Before the render window closes: the shading's textures released."""
        self.set(False)

    def sync(self) -> None:
        """The overlay renderer draws the main renderer's 2-D actors (the main one's passes leave them out)."""
        if self.overlay is None:
            return
        ren = self.plotter.renderer
        wanted = [p for p in _props(ren) if p.IsA("vtkActor2D")]
        have = _props(self.overlay)
        if [id(p) for p in have] == [id(p) for p in wanted]:
            return
        self.overlay.RemoveAllViewProps()
        for prop in wanted:
            self.overlay.AddViewProp(prop)


def _blend_again(win: Any) -> None:
    """The shading pass ends with blending off: the text's antialiased edges need it on."""
    state = win.GetState()
    state.vtkglEnable(0x0BE2)  # GL_BLEND
    state.vtkglBlendFuncSeparate(0x0302, 0x0303, 1, 0x0303)  # SRC_ALPHA, 1 - SRC_ALPHA; ONE, 1 - SRC_ALPHA


def _props(renderer: Any) -> list[Any]:
    props = renderer.GetViewProps()
    props.InitTraversal()
    return [props.GetNextProp() for _ in range(props.GetNumberOfItems())]


def _scene_only_pass() -> Any:
    """Eye-dome shading of VTK's standard render steps without their overlay (2-D) step."""
    from vtkmodules.vtkRenderingOpenGL2 import (vtkCameraPass, vtkEDLShading, vtkRenderPassCollection,
                                                 vtkRenderStepsPass, vtkSequencePass)

    steps = vtkRenderStepsPass()
    steps.SetOverlayPass(None)
    collection = vtkRenderPassCollection()
    collection.AddItem(steps)
    sequence = vtkSequencePass()
    sequence.SetPasses(collection)
    camera = vtkCameraPass()
    camera.SetDelegatePass(sequence)
    edl = vtkEDLShading()
    edl.SetDelegatePass(camera)
    return edl
