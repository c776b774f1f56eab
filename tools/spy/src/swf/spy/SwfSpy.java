package swf.spy;

import java.io.IOException;
import java.lang.reflect.Field;
import java.net.MulticastSocket;
import java.util.List;
import lcm.lcm.LCM;
import lcm.lcm.UDPMulticastProvider;
import lcm.spy.Spy;

/**
 * swf-spy: LCM's own lcm-spy (Debian's liblcm-java, class lcm.spy.Spy) as this project runs it.
 *
 * <p>Three things differ from Debian's lcm-spy script: the JVM options are ones Java 17 accepts
 * (the script's -Xincgc was removed in Java 9), this build's message types (swf_msgs.jar) are on
 * the classpath so that every channel is decoded, and the UDP multicast socket gets a 4 MB
 * receive buffer. LCM's Java provider leaves the buffer at the kernel's default
 * (net.core.rmem_default, 208 KB on Debian), smaller than one hazard map or stereo frame (1.1 MB
 * and 0.4 MB as 64 KB fragments): when the flight process sends a frame group's outputs
 * together, the fragments overflow it and whole messages are lost, so SWF_HAZARD and
 * SWF_LANDMARKS never appear. The kernel caps the buffer at net.core.rmem_max (tools/run raises
 * it); a smaller cap is reported on start.
 */
public final class SwfSpy {
  /** Holds several of the largest messages (the C++ subscribers' recv_buf_size). */
  public static final int RECEIVE_BUFFER_BYTES = 4 << 20;

  private SwfSpy() {}

  /** Opens lcm-spy's window on url (null: LCM_DEFAULT_URL, else LCM's default multicast). */
  public static Spy start(String url) throws IOException, ReflectiveOperationException {
    Spy spy = new Spy(url);
    enlargeReceiveBuffers(spy);
    return spy;
  }

  /**
   * Sets the receive buffer of every UDP multicast socket of the spy's LCM. lcm-spy keeps its
   * LCM instance, and LCM its providers and their sockets, in package-private fields: reached by
   * reflection, as the jar has no other way to configure them.
   */
  static void enlargeReceiveBuffers(Spy spy) throws ReflectiveOperationException, IOException {
    LCM lcm = (LCM) field(Spy.class, "lcm").get(spy);
    List<?> providers = (List<?>) field(LCM.class, "providers").get(lcm);
    for (Object provider : providers) {
      if (!(provider instanceof UDPMulticastProvider)) {
        continue;
      }
      MulticastSocket socket =
          (MulticastSocket) field(UDPMulticastProvider.class, "sock").get(provider);
      socket.setReceiveBufferSize(RECEIVE_BUFFER_BYTES);
      // The JDK halves what Linux reports (twice the request), so this is what was granted.
      int granted = socket.getReceiveBufferSize();
      if (granted < RECEIVE_BUFFER_BYTES) {
        System.err.printf(
            "swf-spy: the kernel granted a %d byte receive buffer, not %d "
                + "(net.core.rmem_max): large messages (SWF_STEREO, SWF_HAZARD) may be lost; "
                + "raise it with: sysctl -w net.core.rmem_max=%d%n",
            granted, RECEIVE_BUFFER_BYTES, RECEIVE_BUFFER_BYTES);
      }
    }
  }

  private static Field field(Class<?> owner, String name) throws NoSuchFieldException {
    Field f = owner.getDeclaredField(name);
    f.setAccessible(true);
    return f;
  }

  private static void usage(java.io.PrintStream out) {
    out.println("usage: swf-spy [-l URL | --lcm-url URL | --lcm-url=URL] [--help] [--version]");
    out.println("lcm-spy (LCM 1.3.1) with the swf message types and a 4 MB UDP receive buffer.");
    out.println("Without a URL: $LCM_DEFAULT_URL, else udpm://239.255.76.67:7667.");
    out.println("Exit codes: 0 window closed, 1 cannot start (no display, no LCM), 2 usage.");
  }

  public static void main(String[] args) {
    String url = null;
    for (int i = 0; i < args.length; ++i) {
      String a = args[i];
      if (a.equals("-h") || a.equals("--help")) {
        usage(System.out);
        return;
      } else if (a.equals("--version")) {
        System.out.println("swf-spy " + System.getProperty("swf.version", "(unknown version)"));
        return;
      } else if ((a.equals("-l") || a.equals("--lcm-url")) && i + 1 < args.length) {
        url = args[++i];
      } else if (a.startsWith("--lcm-url=")) {
        url = a.substring("--lcm-url=".length());
      } else {
        System.err.println("swf-spy: unknown or incomplete argument: " + a);
        usage(System.err);
        System.exit(2);
      }
    }
    try {
      start(url);
    } catch (java.awt.HeadlessException e) {
      System.err.println("swf-spy: no display (set DISPLAY, or run under xvfb-run): " + e);
      System.exit(1);
    } catch (IOException | ReflectiveOperationException e) {
      System.err.println("swf-spy: cannot start: " + e);
      System.exit(1);
    }
  }
}
