#!/usr/bin/env python3
"""A TCP relay that delays every byte by a fixed time each way: the namespace
test's 2 ms link delay on a kernel without tc's netem (tests/deploy/netns_test.sh).

Listens on LISTEN_HOST:LISTEN_PORT; each connection it accepts is joined to a
new one to UPSTREAM_HOST:UPSTREAM_PORT, and what either side sends reaches the
other DELAY_MS later, in order. When either side closes or fails, both go.

Usage: delay_relay.py LISTEN_HOST LISTEN_PORT UPSTREAM_HOST UPSTREAM_PORT DELAY_MS
"""
import asyncio
import sys


async def pump(reader, writer, delay):
    """Copies reader to writer, each chunk held `delay` seconds after it came."""
    loop = asyncio.get_running_loop()
    queue = asyncio.Queue()

    async def receive():
        try:
            while chunk := await reader.read(65536):
                queue.put_nowait((loop.time() + delay, chunk))
        except OSError:
            pass
        queue.put_nowait((loop.time() + delay, None))

    async def send():
        while True:
            due, chunk = await queue.get()
            wait = due - loop.time()
            if wait > 0:
                await asyncio.sleep(wait)
            if chunk is None:
                break
            writer.write(chunk)
            await writer.drain()

    try:
        await asyncio.gather(receive(), send())
    except OSError:
        pass
    finally:
        writer.close()


async def main():
    listen_host, listen_port, upstream_host, upstream_port, delay_ms = sys.argv[1:6]
    delay = float(delay_ms) / 1000

    async def accepted(down_reader, down_writer):
        try:
            up_reader, up_writer = await asyncio.open_connection(upstream_host, int(upstream_port))
        except OSError:
            down_writer.close()
            return
        await asyncio.gather(pump(down_reader, up_writer, delay), pump(up_reader, down_writer, delay))

    server = await asyncio.start_server(accepted, listen_host, int(listen_port))
    async with server:
        await server.serve_forever()


if __name__ == "__main__":
    asyncio.run(main())
