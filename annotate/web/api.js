// The pages' one way to call the server (an ES module shared by app.js and overview.js).
// request() sends the bearer token and returns the Response when it is ok; a lost connection
// (the server restarting) becomes ApiError(0, ...) and a 4xx/5xx an ApiError carrying the
// server's {"error": ...} message.

export class ApiError extends Error {
  // status 0: no response at all (network down, server restarting).
  constructor(status, message) {
    super(message);
    this.status = status;
  }
}

// options: {token, body (sent as JSON), cache (default 'no-store')}
export async function request(method, path, { token, body, cache = 'no-store' } = {}) {
  const headers = token ? { Authorization: `Bearer ${token}` } : {};
  const init = { method, headers, cache };
  if (body !== undefined) {
    headers['Content-Type'] = 'application/json';
    init.body = JSON.stringify(body);
  }
  let res;
  try {
    res = await fetch(path, init);
  } catch {
    throw new ApiError(0, 'no connection to the server');
  }
  if (!res.ok) {
    let message = `${res.status} ${res.statusText} for ${path}`;
    try {
      message = (await res.json()).error || message;
    } catch {
      // not JSON (an empty body or a proxy's error page)
    }
    throw new ApiError(res.status, message);
  }
  return res;
}

// One JSON call: the response's object ({} for an empty body).
export async function api(method, path, options) {
  const res = await request(method, path, options);
  try {
    return (await res.json()) || {};
  } catch {
    return {};
  }
}
