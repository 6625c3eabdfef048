// Runs `retarget annotate serve` as a child process for the browser test: starts it, reads the
// addresses it prints, kills it (SIGKILL, to prove nothing is lost) or stops it (SIGTERM).

import { spawn } from 'node:child_process';

// Every server this process started, killed on exit whatever happens.
const running = new Set();
process.on('exit', () => {
  for (const child of running) child.kill('SIGKILL');
});
// Ctrl-C or a test driver's SIGTERM: exit through the handler above.
for (const signal of ['SIGINT', 'SIGTERM']) process.once(signal, () => process.exit(130));

export class AnnotationServerProcess {
  // retarget: path of the `retarget` binary; project: the annotation project folder;
  // port: 0 for any free one; extra: further arguments (e.g. ['--password', 'secret']).
  constructor({ retarget, project, port = 0, lease = 120, extra = [] }) {
    this.retarget = retarget;
    this.project = project;
    this.port = port;
    this.lease = lease;
    this.extra = extra;
    this.child = null;
    this.output = ''; // stdout and stderr, for failure messages
    this.baseUrl = ''; // http://127.0.0.1:PORT
    this.ownerToken = '';
  }

  // Starts the server; resolves once both addresses are printed. Rejects with the server's
  // output if it exits first or takes longer than timeoutMs.
  async start(timeoutMs = 30000) {
    const args = ['annotate', 'serve', this.project, '--port', String(this.port),
      '--lease', String(this.lease), ...this.extra];
    const child = spawn(this.retarget, args, { stdio: ['ignore', 'pipe', 'pipe'] });
    this.child = child;
    this.output = '';
    running.add(child);
    child.on('exit', () => running.delete(child));

    await new Promise((resolve, reject) => {
      const timer = setTimeout(() => fail(`no addresses printed within ${timeoutMs / 1000} s`), timeoutMs);
      const fail = (why) => {
        clearTimeout(timer);
        reject(new Error(`retarget annotate serve: ${why}\n$ ${this.retarget} ${args.join(' ')}\n${this.output}`));
      };
      const onData = (chunk) => {
        this.output += chunk.toString();
        const annotators = /annotators:\s+(http:\/\/[^\s/]+)\/?\s*$/m.exec(this.output);
        const owner = /owner:\s+\S*\/overview#token=(\S+)/.exec(this.output);
        if (annotators && owner) {
          clearTimeout(timer);
          this.baseUrl = annotators[1];
          this.ownerToken = owner[1];
          this.port = Number(new URL(this.baseUrl).port);
          resolve();
        }
      };
      child.stdout.on('data', onData);
      child.stderr.on('data', (chunk) => {
        this.output += chunk.toString();
      });
      child.on('error', (e) => fail(e.message));
      child.on('exit', (code, signal) => fail(`exited (${signal || code}) before serving`));
    });
    return this;
  }

  get alive() {
    return this.child !== null && this.child.exitCode === null && this.child.signalCode === null;
  }

  // Sends `signal` and waits for the process to end (SIGKILL after graceMs otherwise).
  async stop(signal = 'SIGTERM', graceMs = 5000) {
    const child = this.child;
    if (!child || !this.alive) return;
    const exited = new Promise((resolve) => child.once('exit', resolve));
    child.kill(signal);
    const timer = setTimeout(() => child.kill('SIGKILL'), graceMs);
    await exited;
    clearTimeout(timer);
  }

  kill() {
    return this.stop('SIGKILL');
  }
}

// Runs a command to completion; resolves with its stdout, rejects with all its output on a
// non-zero exit.
export function runCommand(command, args, timeoutMs = 60000) {
  return new Promise((resolve, reject) => {
    const child = spawn(command, args, { stdio: ['ignore', 'pipe', 'pipe'] });
    let output = '';
    let stdout = '';
    child.stdout.on('data', (c) => {
      output += c;
      stdout += c;
    });
    child.stderr.on('data', (c) => (output += c));
    const timer = setTimeout(() => child.kill('SIGKILL'), timeoutMs);
    child.on('error', (e) => {
      clearTimeout(timer);
      reject(new Error(`${command}: ${e.message}`));
    });
    child.on('exit', (code, signal) => {
      clearTimeout(timer);
      if (code === 0) resolve(stdout);
      else reject(new Error(`${command} ${args.join(' ')} failed (${signal || code}):\n${output}`));
    });
  });
}
