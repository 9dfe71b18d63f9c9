package col0rme;

import ij.IJ;
import ij.ImagePlus;
import ij.macro.Interpreter;
import ij.measure.Calibration;
import ij.plugin.BrowserLauncher;

import java.awt.GraphicsEnvironment;
import java.io.File;

/** Opens a run's results as calibrated ImageJ images, and its report. */
final class Results {
	private Results() {}

	/** The files of outdir that exist, in this order: volume (z in nm),
	 *  depth-coded image with its colour bar, support, render. */
	static void open(File outdir) {
		ImagePlus vol = open(outdir, "volume.tif");
		if (vol != null) {
			inNm(vol.getCalibration());
			vol.setProperty("Info", "3D-COL0RME volume: depth bins (z in nm from the coverslip, bin centres) x fine grid\n");
			vol.show();
		}
		for (String name : new String[] { "depth.png", "support.tif", "render.tif" }) {
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
