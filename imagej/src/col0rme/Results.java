package col0rme;

import ij.IJ;
import ij.ImagePlus;
import ij.macro.Interpreter;
import ij.measure.Calibration;
import ij.plugin.BrowserLauncher;
import ij.plugin.LutLoader;
import ij.plugin.frame.Recorder;
import ij.process.LUT;

import java.awt.GraphicsEnvironment;
import java.io.File;

/** Opens a run's results as calibrated ImageJ images, and its report. */
final class Results {
	private Results() {}

	/** The files of outdir that exist, in this order: volume (z in nm),
	 *  the depth map (nm, with a depth lookup table and its calibration
	 *  bar), support, render. */
	static void open(File outdir) {
		ImagePlus vol = open(outdir, "volume.tif");
		double zmax = 0;
		if (vol != null) {
			inNm(vol.getCalibration());
			vol.setProperty("Info", "3D-COL0RME volume: depth bins (z in nm from the coverslip, bin centres) x fine grid\n");
			Calibration c = vol.getCalibration();
			zmax = (vol.getNSlices() - 0.5 - c.zOrigin) * c.pixelDepth;   /* the deepest bin's far edge */
			vol.show();
		}
		ImagePlus depth = open(outdir, "depth.tif");
		if (depth != null) {
			depthMap(depth, zmax);
			depth.show();
			bar(depth);
		}
		for (String name : new String[] { "support.tif", "render.tif" }) {
			ImagePlus imp = open(outdir, name);
			if (imp != null)
				imp.show();
		}
		File html = new File(outdir, "report.html");
		if (html.isFile() && !GraphicsEnvironment.isHeadless() && IJ.getInstance() != null && !Interpreter.isBatchMode()) {
			try {
				BrowserLauncher.openURL(html.toURI().toString());
				return;
			} catch (Exception e) {
				/* no browser: its path in the Log window instead */
			}
		}
		IJ.log("col0rme: results in " + outdir + (html.isFile() ? "; report " + html : ""));
	}

	/* depth.tif as a quantitative map: lateral calibration in nm, values in nm
	 * from the coverslip (0: no signal), a depth lookup table over the depth
	 * range (zmax nm; the map's maximum when unknown). */
	static void depthMap(ImagePlus depth, double zmax) {
		inNm(depth.getCalibration());
		depth.getCalibration().setValueUnit("nm");
		depth.setProperty("Info", "3D-COL0RME depth map: each fine pixel's depth (nm from the coverslip; 0: no signal)\n");
		java.awt.image.IndexColorModel cm = LutLoader.getLut("fire");
		if (cm != null)
			depth.setLut(new LUT(cm, 0, zmax > 0 ? zmax : depth.getStatistics().max));
		depth.setDisplayRange(0, zmax > 0 ? zmax : depth.getStatistics().max);
	}

	/* The calibration bar, as an overlay (Analyze > Tools > Calibration Bar);
	 * with no display at all ImageJ may not draw it: the map goes without. */
	private static void bar(ImagePlus depth) {
		boolean rec = Recorder.record;
		Recorder.record = false;   /* the Recorder writes the plugin's command alone */
		try {
			IJ.run(depth, "Calibration Bar...", "location=[Upper Right] fill=None label=White number=5 decimal=0 font=12 zoom=1 overlay");
		} catch (RuntimeException | Error e) {   /* HeadlessException, no fonts */
			IJ.log("col0rme: depth.tif without its calibration bar (" + e + ")");
		} finally {
			Recorder.record = rec;
		}
	}

	private static ImagePlus open(File dir, String name) {
		File f = new File(dir, name);
		return f.isFile() ? IJ.openImage(f.getPath()) : null;
	}

	/* The CLI writes micrometres (ImageJ's convention): the volume reads in nm,
	 * z included, so a slice's z is its depth bin's centre in nm. */
	static void inNm(Calibration c) {
		double f = Inputs.nmPer(c.getUnit());
		if (f == 0)
			return;
		c.pixelWidth *= f;
		c.pixelHeight *= f;
		c.pixelDepth *= f;
		c.setUnit("nm");
	}
}
