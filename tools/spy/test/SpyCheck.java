import java.awt.Component;
import java.awt.Container;
import java.awt.Frame;
import java.awt.Rectangle;
import java.awt.Robot;
import java.io.File;
import java.nio.file.Files;
import java.nio.file.Path;
import java.util.ArrayList;
import java.util.LinkedHashMap;
import java.util.List;
import java.util.Map;
import javax.imageio.ImageIO;
import javax.swing.JTable;
import javax.swing.SwingUtilities;
import javax.swing.table.TableModel;
import swf.spy.SwfSpy;

/**
 * The test side of swf-spy (spy_test.sh): starts lcm-spy through the launcher's own start()
 * in this JVM (a display is needed: Xvfb), says when it listens (READY file), waits for the
 * list of what the publisher recorded (EXPECTED file, lines "CHANNEL TYPE COUNT"), then reads
 * lcm-spy's channel table, the JTable of its window (the cells the window draws), until every
 * recorded channel is listed with its type decoded and every recorded message counted, with no
 * undecodable message, or until the timeout. Prints the table, saves a screenshot of the window
 * and exits 0 (all listed and counted) or 1 (naming what is missing).
 *
 * <p>usage: SpyCheck READY EXPECTED SCREENSHOT TIMEOUT_S
 */
public final class SpyCheck {
  private SpyCheck() {}

  /** The rows of lcm-spy's channel table, by channel: {column name: cell text}. */
  static Map<String, Map<String, String>> readTable() throws Exception {
    Map<String, Map<String, String>> rows = new LinkedHashMap<>();
    SwingUtilities.invokeAndWait(() -> {
      for (Frame frame : Frame.getFrames()) {
        JTable table = findTable(frame);
        if (table == null || !"LCM Spy".equals(frame.getTitle())) {
          continue;
        }
        TableModel model = table.getModel();
        for (int r = 0; r < table.getRowCount(); ++r) {
          Map<String, String> row = new LinkedHashMap<>();
          for (int c = 0; c < model.getColumnCount(); ++c) {
            row.put(model.getColumnName(c), String.valueOf(table.getValueAt(r, c)));
          }
          rows.put(row.get("Channel"), row);
        }
      }
    });
    return rows;
  }

  static JTable findTable(Component component) {
    if (component instanceof JTable) {
      return (JTable) component;
    }
    if (component instanceof Container) {
      for (Component child : ((Container) component).getComponents()) {
        JTable t = findTable(child);
        if (t != null) {
          return t;
        }
      }
    }
    return null;
  }

  /** What is not yet as recorded: one line per channel, empty when the table shows it all. */
  static List<String> missing(List<String[]> expected, Map<String, Map<String, String>> rows) {
    List<String> out = new ArrayList<>();
    for (String[] e : expected) {
      Map<String, String> row = rows.get(e[0]);
      if (row == null) {
        out.add(e[0] + ": not listed");
      } else if (!row.get("Type").trim().equals(e[1])) {
        out.add(e[0] + ": type '" + row.get("Type") + "', recorded " + e[1]);
      } else if (!row.get("Num Msgs").trim().equals(e[2])) {
        out.add(e[0] + ": " + row.get("Num Msgs").trim() + " messages, recorded " + e[2]);
      } else if (!row.get("Undecodable").trim().equals("0")) {
        out.add(e[0] + ": " + row.get("Undecodable").trim() + " undecodable");
      }
    }
    return out;
  }

  public static void main(String[] args) throws Exception {
    Path ready = Path.of(args[0]);
    Path expectedFile = Path.of(args[1]);
    File screenshot = new File(args[2]);
    long deadline = System.currentTimeMillis() + Long.parseLong(args[3]) * 1000;
    SwfSpy.start(null);
    Files.writeString(ready, "listening\n");
    while (!Files.exists(expectedFile) && System.currentTimeMillis() < deadline) {
      Thread.sleep(100);
    }
    List<String[]> expected = new ArrayList<>();
    if (Files.exists(expectedFile)) {
      for (String line : Files.readAllLines(expectedFile)) {
        if (!line.isBlank()) {
          expected.add(line.trim().split("\\s+"));
        }
      }
    }
    Map<String, Map<String, String>> rows = readTable();
    List<String> missing = missing(expected, rows);
    while (!missing.isEmpty() && System.currentTimeMillis() < deadline) {
      Thread.sleep(200);
      rows = readTable();
      missing = missing(expected, rows);
    }
    System.out.printf("%-20s %-16s %9s %12s%n", "Channel", "Type", "Num Msgs", "Undecodable");
    for (Map<String, String> row : rows.values()) {
      System.out.printf("%-20s %-16s %9s %12s%n", row.get("Channel"), row.get("Type").trim(),
          row.get("Num Msgs").trim(), row.get("Undecodable").trim());
    }
    for (Frame frame : Frame.getFrames()) {
      if ("LCM Spy".equals(frame.getTitle()) && frame.isShowing()) {
        Rectangle bounds = frame.getBounds();
        bounds.setLocation(frame.getLocationOnScreen());
        ImageIO.write(new Robot().createScreenCapture(bounds), "png", screenshot);
      }
    }
    if (expected.isEmpty()) {
      System.out.println("FAIL: no list of recorded channels (" + expectedFile + ")");
      System.exit(1);
    }
    for (String m : missing) {
      System.out.println("FAIL: " + m);
    }
    System.out.printf("%d of %d recorded channels listed with every message decoded%n",
        expected.size() - missing.size(), expected.size());
    System.exit(missing.isEmpty() ? 0 : 1);
  }
}
