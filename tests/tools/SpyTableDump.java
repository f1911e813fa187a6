// SPDX-License-Identifier: Apache-2.0
// A Java agent for tests/tools/spy_headless.sh: inside the lcm-spy JVM that
// tools/spy.sh starts (JAVA_TOOL_OPTIONS=-javaagent:<jar>=<file>), it writes what
// lcm-spy's window shows, every 250 ms, to <file>: the title of each window and
// every row of its channel table (Channel, Type, Num Msgs, ...), tab-separated:
//   window<TAB>LCM Spy
//   columns<TAB>Channel<TAB>Type<TAB>Num Msgs<TAB>...
//   row<TAB>SENSOR_1<TAB>sensor_frame_t<TAB>40<TAB>...
// so that the test can check that lcm-spy decoded our channels with our types. It
// reads the Swing components on the event thread and changes nothing. In any other
// JVM (javac, jar) that picks up the same JAVA_TOOL_OPTIONS it does nothing.
import java.awt.Component;
import java.awt.Container;
import java.awt.Frame;
import java.io.IOException;
import java.nio.charset.StandardCharsets;
import java.nio.file.Files;
import java.nio.file.Path;
import java.nio.file.Paths;
import java.nio.file.StandardCopyOption;
import javax.swing.JTable;
import javax.swing.SwingUtilities;
import javax.swing.table.TableModel;

public final class SpyTableDump {
  private SpyTableDump() {}

  public static void premain(String args) {
    String cmd = System.getProperty("sun.java.command", "");
    if (args == null || args.isEmpty() || !cmd.startsWith("lcm.spy.Spy")) {
      return;
    }
    Path out = Paths.get(args);
    Thread t = new Thread(() -> loop(out), "spy-table-dump");
    t.setDaemon(true);
    t.start();
  }

  private static void loop(Path out) {
    Path tmp = out.resolveSibling(out.getFileName() + ".tmp");
    while (true) {
      try {
        Thread.sleep(250);
        if (!edtRunning()) {
          continue;  // touch nothing of AWT before lcm-spy itself started it
        }
        StringBuilder sb = new StringBuilder();
        SwingUtilities.invokeAndWait(() -> dump(sb));
        if (sb.length() > 0) {
          Files.write(tmp, sb.toString().getBytes(StandardCharsets.UTF_8));
          Files.move(tmp, out, StandardCopyOption.REPLACE_EXISTING, StandardCopyOption.ATOMIC_MOVE);
        }
      } catch (InterruptedException e) {
        return;
      } catch (IOException | java.lang.reflect.InvocationTargetException e) {
        System.err.println("SpyTableDump: " + e);  // the test fails on this line
        return;
      }
    }
  }

  private static boolean edtRunning() {
    for (Thread t : Thread.getAllStackTraces().keySet()) {
      if (t.getName().startsWith("AWT-EventQueue")) {
        return true;
      }
    }
    return false;
  }

  private static void dump(StringBuilder sb) {
    for (Frame f : Frame.getFrames()) {
      if (!f.isShowing()) {
        continue;
      }
      sb.append("window\t").append(f.getTitle()).append('\n');
      tables(f, sb);
    }
  }

  private static void tables(Container c, StringBuilder sb) {
    for (Component k : c.getComponents()) {
      if (k instanceof JTable) {
        TableModel m = ((JTable) k).getModel();
        sb.append("columns");
        for (int j = 0; j < m.getColumnCount(); j++) {
          sb.append('\t').append(m.getColumnName(j));
        }
        sb.append('\n');
        for (int i = 0; i < m.getRowCount(); i++) {
          sb.append("row");
          for (int j = 0; j < m.getColumnCount(); j++) {
            Object v = m.getValueAt(i, j);
            sb.append('\t').append(v == null ? "" : v.toString().trim());
          }
          sb.append('\n');
        }
      }
      if (k instanceof Container) {
        tables((Container) k, sb);
      }
    }
  }
}
