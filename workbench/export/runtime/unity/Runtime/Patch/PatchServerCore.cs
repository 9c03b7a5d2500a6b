// The patch server's network side: a TCP listener on worker threads, one client at a time,
// and a queue that hands each picture to the thread that draws (Unity's main thread).
//
// Plain C# (.NET Framework 4.x, C# 7.2), no UnityEngine. Threads:
//   - the accept thread takes connections; each gets a connection thread;
//   - a connection thread either becomes THE client's (reads lines, answers them) or, while
//     another client is served (after a short grace for one that is just leaving), writes
//     the busy line naming that client and closes;
//   - the drawing thread calls DispatchPending() (Unity: from Update) and the presenter says,
//     later, when a frame showing the picture has been presented; only then is the reply sent.
// The render loop never waits on the network: DispatchPending() only empties a queue.
// A client that vanishes (closes, resets, goes silent past the idle timeout) ends its
// connection thread quietly; the server goes on listening.
using System;
using System.Collections.Concurrent;
using System.Collections.Generic;
using System.Globalization;
using System.IO;
using System.Net;
using System.Net.Sockets;
using System.Threading;

namespace VrColourWorkbench.Patch
{
    /// <summary>Puts a picture on screen and says when a frame showing it has been presented.</summary>
    public interface IPatchPresenter
    {
        /// <summary>
        /// Called on the thread that calls <see cref="PatchServerCore.DispatchPending"/> (in Unity the main
        /// thread). Show <paramref name="command"/> from the next frame on, and call
        /// <see cref="PatchPresentation.Presented"/> once a frame showing it has been presented to the VR
        /// compositor (or <see cref="PatchPresentation.Failed"/> with the reason). May return before that.
        /// </summary>
        void Present(PatchCommand command, PatchPresentation presentation);
    }

    /// <summary>One picture on its way to the screen; the connection thread waits on it.</summary>
    public sealed class PatchPresentation
    {
        readonly ManualResetEvent done = new ManualResetEvent(false);
        string failure;
        int finished;

        public PatchPresentation(PatchCommand command) { Command = command; }

        public PatchCommand Command { get; private set; }

        /// <summary>The connection thread stopped waiting (deadline passed, server stopping): no need to present it.</summary>
        public bool Abandoned { get; internal set; }

        /// <summary>A frame showing the picture has been presented; the reply goes out.</summary>
        public void Presented() { Finish(null); }

        /// <summary>The picture could not be shown; the client gets ok:false with this reason.</summary>
        public void Failed(string reason) { Finish(string.IsNullOrEmpty(reason) ? "no reason given" : reason); }

        void Finish(string reason)
        {
            if (Interlocked.Exchange(ref finished, 1) != 0) return;  // the first word counts
            failure = reason;
            done.Set();
        }

        /// <summary>Waits until presented or failed; false if the deadline passed first.</summary>
        internal bool Wait(TimeSpan timeout, out string reason)
        {
            bool signalled = done.WaitOne(timeout);
            reason = failure;
            return signalled;
        }
    }

    /// <summary>The server: listener, connections, busy replies and the main-thread queue.</summary>
    public sealed class PatchServerCore : IDisposable
    {
        readonly PatchServerOptions options;
        readonly Action<string> log;
        readonly object gate = new object();
        readonly ConcurrentQueue<PatchPresentation> pending = new ConcurrentQueue<PatchPresentation>();
        readonly AutoResetEvent pendingSignal = new AutoResetEvent(false);
        readonly List<Thread> threads = new List<Thread>();
        TcpListener listener;
        Thread acceptThread;
        Connection current;  // the client being served, under gate
        volatile bool stopping;

        /// <param name="options">What the server accepts and its timeouts.</param>
        /// <param name="log">Where to write one-line notes (Unity: Debug.Log); may be null.</param>
        public PatchServerCore(PatchServerOptions options, Action<string> log)
        {
            this.options = options ?? new PatchServerOptions();
            this.log = log ?? (message => { });
        }

        /// <summary>Where the server listens (after <see cref="Start"/>).</summary>
        public IPEndPoint LocalEndpoint { get; private set; }

        /// <summary>Binds and starts listening on a worker thread; port 0 picks a free port (see <see cref="LocalEndpoint"/>).</summary>
        /// <exception cref="SocketException">The address cannot be bound (port in use, no such interface).</exception>
        public void Start(string host, int port)
        {
            if (listener != null) throw new InvalidOperationException("the patch server is already started");
            stopping = false;
            listener = new TcpListener(IPAddress.Parse(host), port);
            listener.Start();
            LocalEndpoint = (IPEndPoint)listener.LocalEndpoint;
            acceptThread = new Thread(AcceptLoop) { IsBackground = true, Name = "patch-server accept" };
            acceptThread.Start();
        }

        /// <summary>
        /// Hands every queued picture to <paramref name="presenter"/>, in order; call it from the drawing
        /// thread (Unity: Update). Returns how many were handed over. Never blocks.
        /// </summary>
        public int DispatchPending(IPatchPresenter presenter)
        {
            int handed = 0;
            PatchPresentation presentation;
            while (pending.TryDequeue(out presentation))
            {
                if (presentation.Abandoned) continue;
                handed++;
                try
                {
                    presenter.Present(presentation.Command, presentation);
                }
                catch (Exception error)  // reported to the client, which decides
                {
                    presentation.Failed(error.Message);
                }
            }
            return handed;
        }

        /// <summary>Waits until a picture is queued (for a host without a render loop); false on timeout.</summary>
        public bool WaitForPending(TimeSpan timeout)
        {
            return !pending.IsEmpty || pendingSignal.WaitOne(timeout);
        }

        /// <summary>Stops listening, drops the client, fails what waits; idempotent.</summary>
        public void Stop()
        {
            stopping = true;
            if (listener != null)
            {
                try { listener.Stop(); } catch (SocketException) { }
            }
            lock (gate)
            {
                if (current != null) current.Drop();
                Monitor.PulseAll(gate);
            }
            PatchPresentation presentation;
            while (pending.TryDequeue(out presentation)) presentation.Failed("the patch server is stopping");
            pendingSignal.Set();
            Thread[] all;
            lock (threads) all = threads.ToArray();
            if (acceptThread != null) acceptThread.Join(2000);
            foreach (var thread in all) thread.Join(2000);
            listener = null;
            acceptThread = null;
        }

        public void Dispose() { Stop(); }

        void AcceptLoop()
        {
            while (!stopping)
            {
                TcpClient client;
                try
                {
                    client = listener.AcceptTcpClient();
                }
                catch (Exception error) when (error is SocketException || error is ObjectDisposedException
                                              || error is InvalidOperationException || error is NullReferenceException)
                {
                    if (!stopping) log("patch server: stopped accepting connections: " + error.Message);
                    return;
                }
                var connection = new Connection(this, client);
                var thread = new Thread(connection.Run) { IsBackground = true, Name = "patch-server connection" };
                lock (threads)
                {
                    threads.RemoveAll(t => !t.IsAlive);
                    threads.Add(thread);
                }
                thread.Start();
            }
        }

        /// <summary>One TCP connection: the served client, or one told that the server is busy.</summary>
        sealed class Connection
        {
            readonly PatchServerCore server;
            readonly TcpClient client;
            readonly string peer;
            string clientName;  // from hello, under server.gate

            public Connection(PatchServerCore server, TcpClient client)
            {
                this.server = server;
                this.client = client;
                var endpoint = client.Client.RemoteEndPoint as IPEndPoint;
                peer = endpoint == null ? "an unknown peer"
                    : endpoint.Address + ":" + endpoint.Port.ToString(CultureInfo.InvariantCulture);
            }

            public void Drop()
            {
                try { client.Client.Shutdown(SocketShutdown.Both); } catch (Exception) { }
                client.Close();
            }

            string Who()
            {
                return string.IsNullOrEmpty(clientName) ? peer : peer + " (" + clientName + ")";
            }

            public void Run()
            {
                Connection served;
                lock (server.gate)
                {
                    var deadline = DateTime.UtcNow + TimeSpan.FromSeconds(server.options.BusyGraceS);
                    while (server.current != null && !server.stopping)
                    {
                        var left = deadline - DateTime.UtcNow;
                        if (left <= TimeSpan.Zero) break;
                        Monitor.Wait(server.gate, left);
                    }
                    served = server.current;
                    if (served == null && !server.stopping) server.current = this;
                }
                if (server.stopping) { client.Close(); return; }
                if (served != null)
                {
                    RefuseBusy(served);
                    return;
                }
                server.log("patch client " + peer + " connected");
                try
                {
                    Serve();
                }
                finally
                {
                    Release();
                    client.Close();
                    if (!server.stopping)  // the presenter may go back to the application's own picture
                    {
                        server.pending.Enqueue(new PatchPresentation(PatchCommand.ClientLeft()));
                        server.pendingSignal.Set();
                    }
                }
            }

            void Release()
            {
                lock (server.gate)
                {
                    if (server.current == this) server.current = null;
                    Monitor.PulseAll(server.gate);
                }
            }

            void RefuseBusy(Connection served)
            {
                string name;
                lock (server.gate) name = served.clientName;
                server.log("patch client " + peer + " refused: busy with " + served.Who());
                try
                {
                    client.SendTimeout = 2000;
                    var stream = client.GetStream();
                    var line = PatchProtocol.Encode(PatchProtocol.BusyReply(served.peer, name));
                    stream.Write(line, 0, line.Length);
                    // Half-close, then read what the client had sent until it closes (at most 1 s):
                    // closing a socket with unread data would reset it and could destroy the busy line.
                    client.Client.Shutdown(SocketShutdown.Send);
                    client.ReceiveTimeout = 1000;
                    var scratch = new byte[PatchProtocol.MaxLineBytes];
                    var until = DateTime.UtcNow.AddSeconds(1);
                    while (DateTime.UtcNow < until && stream.Read(scratch, 0, scratch.Length) > 0) { }
                }
                catch (Exception error) when (error is IOException || error is SocketException || error is ObjectDisposedException)
                {
                }
                finally
                {
                    client.Close();
                }
            }

            void Serve()
            {
                NetworkStream stream;
                try
                {
                    client.NoDelay = true;
                    client.ReceiveTimeout = (int)Math.Min(int.MaxValue, server.options.IdleTimeoutS * 1000.0);
                    client.SendTimeout = 10000;
                    stream = client.GetStream();
                }
                catch (Exception error) when (error is IOException || error is SocketException || error is ObjectDisposedException)
                {
                    return;
                }
                var framer = new PatchLineFramer();
                var frames = new List<byte[]>();
                var buffer = new byte[PatchProtocol.MaxLineBytes];
                while (!server.stopping)
                {
                    int received;
                    try
                    {
                        received = stream.Read(buffer, 0, buffer.Length);
                    }
                    catch (IOException error)
                    {
                        var socketError = error.InnerException as SocketException;
                        if (socketError != null && socketError.SocketErrorCode == SocketError.TimedOut)
                            server.log("patch client " + peer + " silent for "
                                       + server.options.IdleTimeoutS.ToString("R", CultureInfo.InvariantCulture) + " s; dropping it");
                        else
                            server.log("patch client " + peer + ": " + error.Message + "; dropping it");
                        return;
                    }
                    catch (ObjectDisposedException)
                    {
                        return;
                    }
                    if (received == 0)
                    {
                        server.log("patch client " + peer + " closed the connection");
                        return;
                    }
                    frames.Clear();
                    framer.Feed(buffer, 0, received, frames);
                    foreach (var frame in frames)
                    {
                        bool bye;
                        string reply = Answer(frame, out bye);
                        if (bye) Release();  // a client that connects right after its bye is not told "busy"
                        try
                        {
                            var bytes = PatchProtocol.Encode(reply);
                            stream.Write(bytes, 0, bytes.Length);
                        }
                        catch (Exception error) when (error is IOException || error is ObjectDisposedException)
                        {
                            server.log("patch client " + peer + " went away before its reply: " + error.Message);
                            return;
                        }
                        if (bye)
                        {
                            server.log("patch client " + peer + " said bye");
                            return;
                        }
                    }
                }
            }

            string Answer(byte[] frame, out bool bye)
            {
                bye = false;
                if (frame == null) return PatchProtocol.OversizedReply();
                var request = PatchProtocol.Parse(frame, server.options);
                switch (request.Kind)
                {
                    case PatchRequestKind.Hello:
                        lock (server.gate) clientName = request.Client;
                        return request.Reply;
                    case PatchRequestKind.Bye:
                        bye = true;
                        return PatchProtocol.OkReply(request.Id);
                    case PatchRequestKind.Show:
                    case PatchRequestKind.Target:
                        return Present(request);
                    default:
                        return request.Reply;
                }
            }

            string Present(PatchRequest request)
            {
                var presentation = new PatchPresentation(request.Command);
                server.pending.Enqueue(presentation);
                server.pendingSignal.Set();
                var timeout = TimeSpan.FromSeconds(server.options.PresentTimeoutS);
                string failure;
                bool finished = presentation.Wait(timeout, out failure);
                string what = request.Command.Kind == PatchCommandKind.Target
                    ? "the centring target"
                    : PatchCommand.Triple(request.Command.R, request.Command.G, request.Command.B);
                if (!finished)
                {
                    presentation.Abandoned = true;
                    failure = server.stopping
                        ? "the patch server is stopping"
                        : "no frame showing it was presented within "
                          + server.options.PresentTimeoutS.ToString("R", CultureInfo.InvariantCulture)
                          + " s (is the application paused, or in the background without Run In Background?)";
                }
                if (failure != null)
                {
                    server.log("could not present " + request.Command.Describe() + ": " + failure);
                    return PatchProtocol.ErrorReply(request.Id, "could not present " + what + ": " + failure);
                }
                return PatchProtocol.OkReply(request.Id);
            }
        }
    }
}
