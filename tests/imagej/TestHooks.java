import ij.IJ;
import ij.ImagePlus;
import ij.ImageStack;
import ij.WindowManager;
import ij.gui.GenericDialog;
import ij.plugin.frame.Recorder;

import java.awt.Button;
import java.awt.Component;
import java.awt.EventQueue;
import java.awt.Label;
import java.awt.TextField;
import java.awt.Window;
import java.awt.event.ActionEvent;

/** Test hooks for the ImageJ plugin's test, called from -batch macros with
 *  call("TestHooks...."): what a user's hands would do in ImageJ's window. */
public class TestHooks {
	/** Runs an ImageJ command with the Recorder open, as from the menu, and
	 *  returns what the Recorder wrote for it. */
	public static String record(String command, String options) {
		Recorder r = new Recorder(false);
		Recorder.record = true;
		Recorder.recordInMacros = true;
		IJ.run(command, options);
		String text = r.getText();
		r.close();
		return text;
	}

	/** Presses Escape once a child "col0rme COMMAND --progress-json" (the run, not
	 *  its --help-json) has run for a moment. */
	public static String escapeWhileRunning(final String command) {
		Thread t = new Thread(() -> {
			try {
				while (!ProcessHandle.current().descendants().anyMatch(p -> p.info().arguments()
					.map(a -> a.length > 1 && a[0].equals(command) && a[1].equals("--progress-json")).orElse(false)))
					Thread.sleep(20);
				Thread.sleep(300);
			} catch (InterruptedException e) {
				return;
			}
			IJ.setKeyDown(27);
		});
		t.setDaemon(true);
		t.start();
		return "";
	}

	/** One unsaved hyperstack named name with the stacks' frames as its
	 *  channels (ImageJ's czt order), calibrated as the first stack. */
	public static String hyperstack(String titles, String name) {
		String[] t = titles.split(",");
		ImagePlus[] in = new ImagePlus[t.length];
		for (int c = 0; c < t.length; c++)
			in[c] = WindowManager.getImage(t[c]);
		int frames = in[0].getStackSize();
		ImageStack s = new ImageStack(in[0].getWidth(), in[0].getHeight());
		for (int f = 1; f <= frames; f++)
			for (ImagePlus imp : in)
				s.addSlice(imp.getStack().getProcessor(f).duplicate());
		ImagePlus h = new ImagePlus(name, s);
		h.setDimensions(t.length, 1, frames);
		h.setOpenAsHyperStack(true);
		h.setCalibration(in[0].getCalibration().copy());
		h.show();
		return name;
	}

	/** Unsaved copies (titles copy_1, copy_2...) of the stacks; returns their titles. */
	public static String copies(String titles) {
		StringBuilder b = new StringBuilder();
		int k = 1;
		for (String t : titles.split(",")) {
			ImagePlus c = WindowManager.getImage(t).duplicate();
			c.setTitle("copy_" + k++);
			c.show();
			b.append(b.length() > 0 ? "," : "").append(c.getTitle());
		}
		return b.toString();
	}

	/** The image's pixels as raw big-endian data (saveAs needs ImageJ's menus). */
	public static String saveRaw(String title, String path) {
		return new ij.io.FileSaver(WindowManager.getImage(title)).saveAsRawStack(path) ? path : "";
	}

	/** The image as ImageJ's File > Save As > Tiff writes it (the encoder the
	 *  plugin uses for unsaved stacks). */
	public static String saveTiff(String title, String path) {
		ImagePlus copy = WindowManager.getImage(title).duplicate();   /* the image itself keeps no file */
		return new ij.io.FileSaver(copy).saveAsTiffStack(path) ? path : "";
	}

	/** The opened depth map: its value unit, whether its lookup table is a
	 *  colour one, its display range and whether it carries an overlay (the
	 *  calibration bar). */
	public static String depthInfo(String title) {
		ImagePlus imp = WindowManager.getImage(title);
		if (imp == null)
			return "no image " + title;
		return "unit " + imp.getCalibration().getValueUnit() + " colour " + imp.getProcessor().isColorLut()
			+ " range " + imp.getDisplayRangeMin() + "-" + imp.getDisplayRangeMax()
			+ " overlay " + (imp.getOverlay() != null && imp.getOverlay().size() > 0);
	}

	/** A script outside any macro (Groovy, Jython): a failed run is a
	 *  RuntimeException it can catch, and Java goes on. */
	public static void main(String[] args) {
		try {
			col0rme.Col0rme.run3d(args[0]);
			System.out.println("no exception");
		} catch (RuntimeException e) {
			System.out.println("caught: " + e.getMessage());
		}
		System.out.println("java goes on");
		System.exit(0);
	}

	private static volatile String seen = "";

	/** A user at the next dialog titled title: notes the text field labelled
	 *  label (seen()), types value into it (unless empty), presses OK. */
	public static String answer(final String title, final String label, final String value) {
		seen = "";
		Thread t = new Thread(() -> {
			try {
				GenericDialog gd = null;
				while (gd == null) {
					for (Window w : Window.getWindows())
						if (w instanceof GenericDialog && w.isShowing() && title.equals(((GenericDialog) w).getTitle()))
							gd = (GenericDialog) w;
					Thread.sleep(50);
				}
				TextField tf = null;
				boolean next = false;
				for (Component c : gd.getComponents()) {
					if (c instanceof Label)
						next = label.equals(((Label) c).getText());
					else if (next && c instanceof TextField && tf == null)
						tf = (TextField) c;
				}
				seen = tf == null ? "no field " + label : tf.getText();
				if (tf != null && !value.isEmpty())
					tf.setText(value);
				final GenericDialog d = gd;
				final Button ok = gd.getButtons()[0];
				EventQueue.invokeLater(() -> d.actionPerformed(new ActionEvent(ok, ActionEvent.ACTION_PERFORMED, "OK")));
			} catch (InterruptedException e) {
				/* the test ends */
			}
		});
		t.setDaemon(true);
		t.start();
		return "";
	}

	public static String seen() {
		return seen;
	}

	/** The stages the plugin's last run with progress finished, from the
	 *  CLI's --progress-json lines (col0rme.Cli.stagesDone, package-private). */
	public static String stagesDone() {
		try {
			java.lang.reflect.Field f = Class.forName("col0rme.Cli").getDeclaredField("stagesDone");
			f.setAccessible(true);
			return (String) f.get(null);
		} catch (Exception e) {
			return "unreadable: " + e;
		}
	}
}
