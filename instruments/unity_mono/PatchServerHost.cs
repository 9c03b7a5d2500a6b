// A console host for the Unity package's patch-server core (VrColourWorkbench.Patch), run under mono.
//
// It runs the very code VrPatchServer runs in Unity (PatchProtocol, PatchJson, PatchServerCore)
// on a real TCP socket, with a headless presenter in place of the headset: it "presents" each
// picture at once (no frame, nothing drawn), logs it and, with --record FILE, appends it to FILE
// as one JSON line (the same lines as the Python reference server's --record). The main thread
// plays Unity's main thread: it waits for queued pictures and dispatches them.
//
// Built and started by `python -m instruments.patch_server --impl unity-mono --port 0`, which
// prints (from here) the same line as the Python reference server:
//   patch server (vr-workbench-patch/1) listening on tcp:127.0.0.1:PORT
using System;
using System.Globalization;
using System.IO;
using System.Net.Sockets;
using System.Text;
using VrColourWorkbench.Patch;

namespace VrColourWorkbench.MonoHost
{
    /// <summary>Shows nothing: presents each picture at once and records it.</summary>
    sealed class HeadlessPresenter : IPatchPresenter
    {
        readonly StreamWriter record;

        public HeadlessPresenter(StreamWriter record) { this.record = record; }

        public void Present(PatchCommand command, PatchPresentation presentation)
        {
            Console.Error.WriteLine(DateTime.Now.ToString("yyyy-MM-dd HH:mm:ss,fff", CultureInfo.InvariantCulture)
                                    + (command.Kind == PatchCommandKind.ClientLeft
                                       ? " the client has left: the application would show its own picture again"
                                       : " showing " + command.Describe() + " (headless: nothing drawn)"));
            if (record != null && command.Kind != PatchCommandKind.ClientLeft)
            {
                record.WriteLine(command.ToRecord());
                record.Flush();
            }
            presentation.Presented();
        }
    }

    static class PatchServerHost
    {
        const string Usage = "usage: mono PatchServerHost.exe --port PORT [--host ADDR] [--idle-timeout S] [--record FILE]"
                             + " [--display-name TEXT] [--no-apl] [--no-eye] [--no-target]";

        static int Main(string[] args)
        {
            string host = "127.0.0.1";
            int port = -1;
            string recordPath = null;
            var options = new PatchServerOptions { DisplayName = "Unity VrPatchServer core under mono (headless: nothing drawn)" };
            try
            {
                for (int i = 0; i < args.Length; i++)
                {
                    switch (args[i])
                    {
                        case "--host": host = args[++i]; break;
                        case "--port": port = int.Parse(args[++i], CultureInfo.InvariantCulture); break;
                        case "--idle-timeout": options.IdleTimeoutS = double.Parse(args[++i], CultureInfo.InvariantCulture); break;
                        case "--record": recordPath = args[++i]; break;
                        case "--display-name": options.DisplayName = args[++i]; break;
                        case "--no-apl": options.AplPatches = false; break;
                        case "--no-eye": options.EyeField = false; break;
                        case "--no-target": options.TargetCommand = false; break;
                        default: throw new ArgumentException("unknown argument " + args[i]);
                    }
                }
                if (port < 0 || port > 65535) throw new ArgumentException("--port PORT (0..65535) is required");
            }
            catch (Exception error) when (error is ArgumentException || error is FormatException
                                          || error is IndexOutOfRangeException || error is OverflowException)
            {
                Console.Error.WriteLine("error: " + error.Message);
                Console.Error.WriteLine(Usage);
                return 2;
            }

            StreamWriter record = recordPath == null ? null : new StreamWriter(recordPath, true, new UTF8Encoding(false));
            var core = new PatchServerCore(options, message => Console.Error.WriteLine(
                DateTime.Now.ToString("yyyy-MM-dd HH:mm:ss,fff", CultureInfo.InvariantCulture) + " " + message));
            try
            {
                core.Start(host, port);
            }
            catch (Exception error) when (error is SocketException || error is FormatException)
            {
                Console.Error.WriteLine("error: cannot listen on " + host + ":" + port.ToString(CultureInfo.InvariantCulture)
                                        + " (" + error.Message + "); choose another --port");
                return 2;
            }
            var endpoint = core.LocalEndpoint;
            Console.Out.WriteLine("patch server (" + PatchProtocol.Name + ") listening on tcp:" + endpoint.Address + ":"
                                  + endpoint.Port.ToString(CultureInfo.InvariantCulture));
            Console.Out.Flush();

            var stop = new System.Threading.ManualResetEvent(false);
            Console.CancelKeyPress += (sender, e) => { e.Cancel = true; stop.Set(); };
            var presenter = new HeadlessPresenter(record);
            while (!stop.WaitOne(0))
            {
                if (core.WaitForPending(TimeSpan.FromMilliseconds(200))) core.DispatchPending(presenter);
            }
            core.Stop();
            if (record != null) record.Dispose();
            return 0;
        }
    }
}
