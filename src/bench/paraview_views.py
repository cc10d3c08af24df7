"""ParaView's side of anvil's views benchmark (docs/bench/views.md, "Against ParaView").

Run by `anvil bench --views-only --paraview` through pvbatch (under xvfb-run when there is no
display); it can be run by hand the same way:

    xvfb-run -a pvbatch src/bench/paraview_views.py --volume VOLUME.nc --sun 210,35 \
        --size 160x120 --repeats 3 --out DIR [--anvil N:SHARED:STILL:REBUILD:VIEW,...] \
        [--images DIR]

VOLUME.nc is the extinction file `anvil bench --paraview` writes from the volume it benchmarks
(docs/data.md, "Extinction files"): beta_ice and beta_water per voxel, m^-1.  The script
renders the views anvil's bench_views (src/bench/bench.c) renders -- N = 1, 2, 8 and 12 cameras
orbiting the box, the same orbit formula, field of view and image size -- with VTK's GPU ray
caster three ways: with volumetric shadows (VolumetricScatteringBlending 2, shadow rays
through the whole volume, GlobalIlluminationReach 1), with gradient shading only (no shadows,
for reference), and with the volume hidden (ParaView's fixed cost of a render).  Each frame is
N renders; frames are repeated and the median is kept.  It prints a
CSV on stdout and writes DIR/views-paraview.csv and DIR/views-paraview.md (anvil's numbers from
--anvil beside ParaView's).  --images DIR also saves two of the views (azimuth 20: against
the sun; azimuth 200: the sunlit side) in each mode as PNG.

The extinction enters as VTK's scalar opacity: with ScalarOpacityUnitDistance u, VTK turns an
opacity a over a step d into 1 - (1 - a)^(d / u); an opacity function a(beta) = 1 - exp(-beta u)
therefore gives the Beer-Lambert transmittance exp(-beta d) of every step, the same extinction
anvil integrates.  The colour is white: the cloud scatters whatever light reaches it.
"""

import argparse
import math
import statistics
import sys
import time

from paraview import servermanager
from paraview.simple import (AddLight, CreateView, GetColorTransferFunction,
                             GetOpacityTransferFunction, NetCDFReader, SaveScreenshot, Show,
                             TrivialProducer)
from vtkmodules.util import numpy_support
from vtkmodules.vtkCommonDataModel import vtkImageData

COUNTS = (1, 2, 8, 12)
OPACITY_UNIT_M = 10.0   # ScalarOpacityUnitDistance: keeps a(beta) below 1 for the storm's beta
OPACITY_POINTS = 96     # samples of a(beta) = 1 - exp(-beta u) in the piecewise function
IMAGE_VIEWS = ((1, 0), (12, 6))  # (views, index): azimuth 20 (against the sun) and 200 (sunlit)
# Henyey-Greenstein g of VTK's scattering.  anvil's phases are forward-peaked (g 0.86 water,
# 0.75 ice), but VTK has single scattering only, no forward-scattered light in the cloud and no
# exposure: with g 0.8 the sunlit side, seen at ~130 degrees from the sun, renders almost black.
# Isotropic scattering gives the picture closest to anvil's; g does not change the cost.
ANISOTROPY = 0.0
MIN_REPEATS = 5         # ParaView frames per view count at least (a shared machine is noisy)


def parse():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--volume", required=True, help="extinction file from anvil bench --paraview")
    p.add_argument("--sun", default="210,35", help="azimuth,elevation in degrees (anvil's)")
    p.add_argument("--size", default="160x120", help="image size WxH")
    p.add_argument("--repeats", type=int, default=3, help="frames per view count (median)")
    p.add_argument("--anvil", default="", help="anvil's rows N:shared:still:rebuild:view,...")
    p.add_argument("--out", default=".", help="where views-paraview.{csv,md} go")
    p.add_argument("--images", default="", help="where the first view's PNGs go")
    a = p.parse_args()
    a.sun = [float(x) for x in a.sun.split(",")]
    a.width, a.height = (int(x) for x in a.size.lower().split("x"))
    return a


def direction(azimuth_deg, elevation_deg):
    """anvil's camera_direction: azimuth clockwise from north (+y), x east, z up."""
    az, el = math.radians(azimuth_deg), math.radians(elevation_deg)
    return (math.sin(az) * math.cos(el), math.cos(az) * math.cos(el), math.sin(el))


def load_volume(path):
    """The extinction file as point data on voxel centres (anvil samples beta trilinearly on
    voxel centres), beta = beta_ice + beta_water.  Returns the producer, the box and beta max."""
    reader = NetCDFReader(FileName=[path])
    reader.Dimensions = "(z, y, x)"
    reader.OutputType = "Image"
    reader.UpdatePipeline()
    cells = servermanager.Fetch(reader)
    data = cells.GetCellData()
    beta = (numpy_support.vtk_to_numpy(data.GetArray("beta_ice")) +
            numpy_support.vtk_to_numpy(data.GetArray("beta_water"))).astype("float32")
    # The CF reader puts the first grid point on the first cell centre and gives the values
    # as cell data, so its image is shifted by half a voxel; rebuild it with the values on
    # the centres.
    n = [e1 - e0 for e0, e1 in zip(cells.GetExtent()[0::2], cells.GetExtent()[1::2])]
    b = cells.GetBounds()
    spacing = [(b[2 * a + 1] - b[2 * a]) / n[a] for a in range(3)]
    image = vtkImageData()
    image.SetDimensions(*n)
    image.SetSpacing(*spacing)
    image.SetOrigin(*(b[2 * a] for a in range(3)))
    array = numpy_support.numpy_to_vtk(beta, deep=1)
    array.SetName("beta")
    image.GetPointData().SetScalars(array)
    producer = TrivialProducer()
    producer.GetClientSideObject().SetOutput(image)
    producer.UpdatePipeline()
    box = [(b[2 * a] - 0.5 * spacing[a], b[2 * a] + (n[a] - 0.5) * spacing[a]) for a in range(3)]
    return producer, box, float(beta.max()), n


def orbit_views(box, count):
    """bench_views' cameras: azimuth 360 i / n + 20, elevation 15 + 10 (i mod 3), distance
    1.2 x the box diagonal, looking at the box centre, z up, 50 degrees vertical."""
    centre = [0.5 * (lo + hi) for lo, hi in box]
    diag = math.sqrt(sum((hi - lo) ** 2 for lo, hi in box))
    eyes = []
    for i in range(count):
        d = direction(360.0 * i / count + 20.0, 15.0 + 10.0 * (i % 3))
        eyes.append([centre[a] + 1.2 * diag * d[a] for a in range(3)])
    return centre, diag, eyes


def setup(producer, box, beta_max, sun, width, height):
    view = CreateView("RenderView")
    view.ViewSize = [width, height]
    view.OrientationAxesVisibility = 0
    view.Background = [0.30, 0.45, 0.75]  # anvil's sky (linear; no tone mapping here)
    if view.GetProperty("UseColorPaletteForBackground") is not None:
        view.UseColorPaletteForBackground = 0
    # The sun only: the light kit (key, fill, back and head lights, all tied to the camera)
    # off, one directional light fixed in the scene.
    view.UseLight = 0
    centre, diag, _ = orbit_views(box, 1)
    s = direction(*sun)
    light = AddLight(view=view)
    light.Coords = "Scene"
    light.Type = "Directional"
    light.Position = [centre[a] + diag * s[a] for a in range(3)]
    light.FocalPoint = centre
    light.Intensity = 1.0
    display = Show(producer, view)
    display.SetRepresentationType("Volume")
    display.ColorArrayName = ["POINTS", "beta"]
    display.VolumeRenderingMode = "GPU Based"
    lut = GetColorTransferFunction("beta")
    lut.RGBPoints = [0.0, 1.0, 1.0, 1.0, beta_max, 1.0, 1.0, 1.0]
    pwf = GetOpacityTransferFunction("beta")
    points = []
    for k in range(OPACITY_POINTS):
        # denser near zero, where most of the storm's voxels are
        b = beta_max * (k / (OPACITY_POINTS - 1)) ** 2
        points += [b, 1.0 - math.exp(-b * OPACITY_UNIT_M), 0.5, 0.0]
    pwf.Points = points
    display.ScalarOpacityFunction = pwf
    display.ScalarOpacityUnitDistance = OPACITY_UNIT_M
    display.Ambient = 0.0
    display.Diffuse = 1.0
    display.Specular = 0.0
    camera = view.GetActiveCamera()
    camera.SetViewAngle(50.0)
    camera.SetViewUp(0.0, 0.0, 1.0)
    view.CameraParallelProjection = 0
    # The ray step is VTK's own: ParaView 5.11 gives this representation no sample distance
    # setting, and its mapper (vtkMultiBlockVolumeMapper) exposes none to Python.
    return view, display


def show(display, view, mode):
    """Shadowed, gradient-shaded, or hidden ("no volume": ParaView's fixed cost of a render)."""
    shadows = mode == "shadows"
    display.Visibility = 0 if mode == "no volume" else 1
    display.Shade = 1
    if shadows:
        display.VolumetricScatteringBlending = 2.0   # scattering (shadow rays) only
        display.GlobalIlluminationReach = 1.0        # shadow rays cross the whole volume
    else:
        display.VolumetricScatteringBlending = 0.0   # gradient (surface-like) shading only
        display.GlobalIlluminationReach = 0.0
    if display.GetProperty("VolumeAnisotropy") is not None:
        display.VolumeAnisotropy = ANISOTROPY
    if view.GetProperty("VolumeAnisotropy") is not None:
        view.VolumeAnisotropy = ANISOTROPY


def render(view, window, centre, eye):
    camera = view.GetActiveCamera()
    camera.SetFocalPoint(*centre)
    camera.SetPosition(*eye)
    camera.SetViewUp(0.0, 0.0, 1.0)
    t = time.perf_counter()
    view.StillRender()
    window.WaitForCompletion()  # llvmpipe renders when flushed: time the finished frame
    return 1000.0 * (time.perf_counter() - t)


def spread(values):
    return 0.5 * (max(values) - min(values))


def main():
    a = parse()
    producer, box, beta_max, n = load_volume(a.volume)
    view, display = setup(producer, box, beta_max, a.sun, a.width, a.height)
    window = view.GetRenderWindow()
    window.SetSize(a.width, a.height)
    modes = ("shadows", "no shadows", "no volume")
    for mode in modes:
        show(display, view, mode)
        centre, diag, eyes = orbit_views(box, 1)
        for _ in range(3):  # warm up: shader variants, texture upload
            render(view, window, centre, eyes[0])
        if a.images and mode != "no volume":
            for count, i in IMAGE_VIEWS:
                centre, diag, eyes = orbit_views(box, count)
                render(view, window, centre, eyes[i])
                name = "bench-paraview%s-az%d.png" % ("" if mode == "shadows" else "-noshadow",
                                                       round(360.0 * i / count + 20.0))
                SaveScreenshot("%s/%s" % (a.images, name), view,
                               ImageResolution=[a.width, a.height])
                print("wrote %s/%s (camera at %s m, looking at %s m)"
                      % (a.images, name, ", ".join("%.1f" % x for x in eyes[i]),
                         ", ".join("%.1f" % x for x in centre)))
    # The modes take turns within each repeat, so a busy machine slows them alike.
    repeats = max(MIN_REPEATS, a.repeats)
    results = []
    for count in COUNTS:
        centre, diag, eyes = orbit_views(box, count)
        frames = {m: [] for m in modes}
        per_view = {m: [] for m in modes}
        for _ in range(repeats):
            for mode in modes:
                show(display, view, mode)
                render(view, window, centre, eyes[0])  # untimed: the mode's first render
                ms = [render(view, window, centre, e) for e in eyes]
                frames[mode].append(sum(ms))
                per_view[mode] += ms
        for mode in modes:
            results.append({"mode": mode, "views": count,
                            "frame_ms": statistics.median(frames[mode]),
                            "frame_spread": spread(frames[mode]),
                            "view_ms": statistics.median(per_view[mode])})
    info = window.ReportCapabilities().splitlines()
    device = next((l.split(":", 1)[1].strip() for l in info if "renderer string" in l), "?")
    version = next((l.split(":", 1)[1].strip() for l in info if "version string" in l), "?")
    manager = servermanager.vtkSMProxyManager
    pv = "%d.%d.%d" % (manager.GetVersionMajor(), manager.GetVersionMinor(),
                       manager.GetVersionPatch())

    anvil = {}
    for row in filter(None, a.anvil.split(",")):
        f = row.split(":")
        anvil[int(f[0])] = [float(x) for x in f[1:5]]

    csv = ["renderer,mode,views,frame_ms,frame_spread_ms,view_ms"]
    for count, (shared, still, rebuild, view_ms) in sorted(anvil.items()):
        csv.append("anvil,shared light map after a change,%d,%.3f,,%.3f" % (count, shared,
                                                                          shared / count))
        csv.append("anvil,shared light map without a change,%d,%.3f,,%.3f" % (count, still,
                                                                            still / count))
        csv.append("anvil,a build per view,%d,%.3f,,%.3f" % (count, rebuild, rebuild / count))
    for r in results:
        csv.append("paraview,%s,%d,%.3f,%.3f,%.3f" % (r["mode"], r["views"], r["frame_ms"],
                                                       r["frame_spread"], r["view_ms"]))
    text = "\n".join(csv) + "\n"
    sys.stdout.write(text)
    with open("%s/views-paraview.csv" % a.out, "w") as f:
        f.write(text)

    pvs = {(r["mode"], r["views"]): r for r in results}
    md = ["<!-- generated by `anvil bench --views-only --paraview` "
          "(src/bench/paraview_views.py); do not edit by hand -->",
          "| views | anvil, shared light map: frame after a change, ms | anvil: frame without "
          "a change, ms | anvil: a build per view, ms | ParaView, volumetric shadows: frame, "
          "ms | ParaView, no shadows: frame, ms | ParaView, volume hidden: frame, ms | "
          "ParaView shadowed ÷ anvil after a change | ParaView shadowed ÷ anvil without a "
          "change | per view: anvil after a change / ParaView shadowed, ms |",
          "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for count in COUNTS:
        sh, ns, nv = (pvs[(m, count)] for m in ("shadows", "no shadows", "no volume"))
        pv_cols = "%.0f ± %.0f | %.0f ± %.0f | %.0f ± %.0f" % (
            sh["frame_ms"], sh["frame_spread"], ns["frame_ms"], ns["frame_spread"],
            nv["frame_ms"], nv["frame_spread"])
        if count in anvil:
            shared, still, rebuild, _ = anvil[count]
            md.append("| %d | %.0f | %.0f | %.0f | %s | %.1f | %.1f | %.0f / %.0f |"
                      % (count, shared, still, rebuild, pv_cols, sh["frame_ms"] / shared,
                         sh["frame_ms"] / still, shared / count, sh["view_ms"]))
        else:
            md.append("| %d | | | | %s | | | / %.0f |" % (count, pv_cols, sh["view_ms"]))
    md.append("")
    md.append("ParaView %s, GPU ray cast mapper (VTK's own ray step), %dx%d px, %dx%dx%d voxels "
              "(beta = beta_ice + beta_water on voxel centres), one directional light from "
              "azimuth %g, elevation %g; VolumetricScatteringBlending 2, GlobalIllumination"
              "Reach 1, anisotropy %g; medians of %d frames (± half their range), the three "
              "ParaView modes taking turns within each repeat.  Device: %s (OpenGL %s)."
              % (pv, a.width, a.height, n[0], n[1], n[2], a.sun[0], a.sun[1], ANISOTROPY,
                 repeats, device, version))
    with open("%s/views-paraview.md" % a.out, "w") as f:
        f.write("\n".join(md) + "\n")
    print("wrote %s/views-paraview.csv and %s/views-paraview.md" % (a.out, a.out))


if __name__ == "__main__":
    main()
