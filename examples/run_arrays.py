"""The whole method on numpy arrays: simulate three small acquisitions with
the library's simulator, run 3D-COL0RME on them, look at the result."""
import col0rme

sim = col0rme.simulate(width=24, height=24, frames=200, angles=[62, 65, 68], filaments=2)
res = col0rme.run(sim.stacks, angles=sim.angles, pixel_size_nm=sim.pixel_size_nm, fwhm_nm=sim.fwhm_nm,
                  wavelength_nm=488, n_sample=1.33)   # the excitation and the sample index: say them

print("volume", res.volume.shape, "depth bins %g..%g nm" % (res.z_nm[0], res.z_nm[-1]))
seen = res.support & (res.depth > 0)
print("%d support pixels with a depth, mean depth %.0f nm" % (seen.sum(), res.depth[seen].mean()))
print("seconds per step:", res.report["timings_s"])

try:                          # errors name the parameter at fault
    col0rme.run(sim.stacks[:2], angles=sim.angles, pixel_size_nm=100, fwhm_nm=229)
except col0rme.Error as e:
    print("refused:", e)
