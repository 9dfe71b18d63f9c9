package col0rme;

import ij.IJ;
import ij.ImagePlus;
import ij.WindowManager;
import ij.gui.Roi;
import ij.plugin.Duplicator;
import ij.io.FileInfo;
import ij.io.FileSaver;
import ij.io.TiffEncoder;
import ij.measure.Calibration;

import java.io.BufferedOutputStream;
import java.io.DataOutputStream;
import java.io.File;
import java.io.FileOutputStream;
import java.io.IOException;
import java.math.BigDecimal;
import java.math.MathContext;
import java.nio.file.Files;
import java.util.ArrayList;
import java.util.List;

/** The open stacks a run reads: picked by title, checked, and handed to the
 *  CLI as files: a stack that came unchanged from a TIFF by its path, any
 *  other written to a temporary folder (removed by close()). */
final class Inputs implements AutoCloseable {
	final List<ImagePlus> images = new ArrayList<ImagePlus>();
	final List<String> paths = new ArrayList<String>();
	private final List<String> given = new ArrayList<String>();   /* a file named in stacks=, else null */
	private File tmp;

	/** Titles of the open images with more than one frame, in the order they were opened. */
	static String openStacks() {
		StringBuilder b = new StringBuilder();
		int[] ids = WindowManager.getIDList();
		if (ids != null)
			for (int id : ids) {
				ImagePlus imp = WindowManager.getImage(id);
				if (imp != null && imp.getStackSize() > 1 && imp.getBitDepth() != 24)
					b.append(b.length() > 0 ? "," : "").append(imp.getTitle());
			}
		return b.toString();
	}

	/** Open images by title, or TIFF files by path (with no display ImageJ
	 *  cannot open images: a batch process names the files). */
	static Inputs pick(String titles) throws Failure {
		Inputs in = new Inputs();
		if (titles.trim().isEmpty())
			throw new Failure("col0rme: no stacks: open one stack per angle (or one hyperstack) and name them in stacks=");
		for (String t : titles.split(",")) {
			t = t.trim();
			ImagePlus imp = WindowManager.getImage(t);
			String path = null;
			if (imp == null && new File(t).isFile()) {
				imp = IJ.openVirtual(t);   /* the header only: size and calibration */
				if (imp == null)
					throw new Failure("col0rme: stacks: " + t + " is not a TIFF that ImageJ reads");
				path = new File(t).getAbsolutePath();
			}
			if (imp == null)
				throw new Failure("col0rme: stacks: no open image is titled '" + t + "' and no file is named so");
			if (imp.getBitDepth() == 24)
				throw new Failure("col0rme: stack '" + imp.getTitle() + "' is RGB: give the camera's grey-level stack");
			in.images.add(imp);
			in.given.add(path);
		}
		ImagePlus a = in.images.get(0);
		for (ImagePlus b : in.images)
			if (b.getWidth() != a.getWidth() || b.getHeight() != a.getHeight())
				throw new Failure("col0rme: stack '" + b.getTitle() + "' is " + b.getWidth() + "x" + b.getHeight() + " pixels but '"
					+ a.getTitle() + "' is " + a.getWidth() + "x" + a.getHeight() + ": the stacks must have the same size");
		return in;
	}

	/** A rectangular selection and a frame range ("first-last", 1-based;
	 *  empty: all) honoured: the stacks cropped to the selection (the first
	 *  stack's that has one: the angles share one field of view) and cut to
	 *  the frames, then handed to the CLI as temporary files. A selection
	 *  that is not a rectangle, or a range outside the frames, is refused.
	 *  Returns what was restricted, for the log (empty: nothing). */
	String restrict(String frames) throws Failure {
		Roi roi = null;
		for (ImagePlus imp : images)
			if (roi == null && imp.getRoi() != null && imp.getRoi().isArea())
				roi = imp.getRoi();
		if (roi != null && roi.getType() != Roi.RECTANGLE)
			throw new Failure("col0rme: the selection on the stacks is not a rectangle: col0rme runs on rectangles "
				+ "(draw one, or Edit > Selection > Select None)");
		int n = frames(images.get(0)), f0 = 1, f1 = n;
		if (!frames.trim().isEmpty()) {
			java.util.regex.Matcher m = java.util.regex.Pattern.compile("\\s*(\\d+)\\s*-\\s*(\\d+)\\s*").matcher(frames);
			if (!m.matches())
				throw new Failure("col0rme: frames=" + frames + ": expected FIRST-LAST (1-based, e.g. 1-500)");
			f0 = Integer.parseInt(m.group(1));
			f1 = Integer.parseInt(m.group(2));
			for (ImagePlus imp : images)
				if (f0 < 1 || f1 < f0 || f1 > frames(imp))
					throw new Failure("col0rme: frames=" + frames + ": stack '" + imp.getTitle() + "' has frames 1-" + frames(imp));
		}
		if (roi == null && f0 == 1 && f1 == n)
			return "";
		for (int i = 0; i < images.size(); i++) {
			ImagePlus imp = images.get(i);
			Roi own = imp.getRoi();
			imp.setRoi(roi == null ? null : (Roi) roi.clone());
			boolean hyper = imp.isHyperStack() || imp.getNChannels() > 1, inT = imp.getNFrames() > 1;
			ImagePlus c = !hyper ? new Duplicator().run(imp, f0, f1)
				: inT ? new Duplicator().run(imp, 1, imp.getNChannels(), 1, imp.getNSlices(), f0, f1)
				: new Duplicator().run(imp, 1, imp.getNChannels(), f0, f1, 1, 1);
			imp.setRoi(own);
			c.setTitle(imp.getTitle());
			images.set(i, c);
			given.set(i, null);   /* written as a temporary file */
		}
		java.awt.Rectangle r = roi != null ? roi.getBounds() : null;
		return (r != null ? "the selection x " + r.x + " y " + r.y + ", " + r.width + "x" + r.height + " pixels" : "")
			+ (r != null && (f0 != 1 || f1 != n) ? ", " : "") + (f0 != 1 || f1 != n ? "frames " + f0 + "-" + f1 : "");
	}

	/* A stack's frames: a hyperstack's time points, else its planes. */
	private static int frames(ImagePlus imp) {
		if (!imp.isHyperStack() && imp.getNChannels() == 1)
			return imp.getStackSize();
		return imp.getNFrames() > 1 ? imp.getNFrames() : imp.getNSlices();
	}

	/** The number of stacks the CLI will see: a hyperstack's channels count one each. */
	int count() {
		if (images.size() == 1)
			return Math.max(1, images.get(0).getNChannels());
		return images.size();
	}

	void checkCount(int nangles) throws Failure {
		if (nangles == 0 || nangles == count())
			return;
		throw new Failure("col0rme: " + nangles + " angles but " + count() + (count() == 1 ? " stack" : " stacks")
			+ ": give one stack per angle, in acquisition order, or one hyperstack with the angles as channels");
	}

	/** The pixel size in nm from the first stack's calibration, or null. */
	String calibratedPixelNm() {
		Calibration c = images.get(0).getCalibration();
		double f = nmPer(c.getUnit());
		if (!c.scaled() || f == 0 || !(c.pixelWidth > 0))
			return null;
		return new BigDecimal(c.pixelWidth * f).round(new MathContext(12)).stripTrailingZeros().toPlainString();
	}

	void checkCalibrated() throws Failure {
		for (ImagePlus imp : images) {
			Calibration c = imp.getCalibration();
			if (!c.scaled() || nmPer(c.getUnit()) == 0)
				throw new Failure("col0rme: stack '" + imp.getTitle()
					+ "' has no pixel size in its calibration: give the pixel size (pixel=NM, Image > Properties...)");
		}
	}

	static double nmPer(String unit) {
		if (unit == null)
			return 0;
		switch (unit) {
		case "nm": return 1;
		case "um": case "\u00b5m": case "\u03bcm": case "micron": case "microns": return 1000;
		case "mm": return 1e6;
		default: return 0;
		}
	}

	/** The files the CLI reads, writing the stacks that have none. */
	void write() throws Failure {
		for (int i = 0; i < images.size(); i++) {
			ImagePlus imp = images.get(i);
			File f = given.get(i) != null ? new File(given.get(i)) : fileOf(imp);
			if (f == null) {
				try {
					if (tmp == null)
						tmp = Files.createTempDirectory("col0rme-in").toFile();
					f = new File(tmp, String.format("stack_%02d.tif", paths.size() + 1));
					writeTiff(imp, f);
				} catch (IOException e) {
					close();
					throw new Failure("col0rme: cannot write stack '" + imp.getTitle() + "' to a temporary file: " + e.getMessage());
				}
			}
			paths.add(f.getAbsolutePath());
		}
	}

	/* The TIFF the image came from, when it is unchanged and whole. */
	private static File fileOf(ImagePlus imp) {
		FileInfo fi = imp.getOriginalFileInfo();
		if (fi == null || fi.fileFormat != FileInfo.TIFF || fi.directory == null || fi.fileName == null || imp.changes
			|| imp.getStack().isVirtual())
			return null;
		File f = new File(fi.directory, fi.fileName);
		return f.isFile() && fi.nImages == imp.getStackSize() ? f : null;
	}

	/* As File > Save As > Tiff does, without renaming the image. */
	private static void writeTiff(ImagePlus imp, File f) throws IOException {
		FileInfo fi = imp.getFileInfo();
		fi.description = new FileSaver(imp).getDescriptionString();
		fi.info = imp.getInfoProperty();
		try (DataOutputStream out = new DataOutputStream(new BufferedOutputStream(new FileOutputStream(f), 1 << 20))) {
			new TiffEncoder(fi).write(out);
		}
	}

	@Override
	public void close() {
		if (tmp == null)
			return;
		File[] fs = tmp.listFiles();
		if (fs != null)
			for (File f : fs)
				f.delete();
		tmp.delete();
		tmp = null;
	}
}
